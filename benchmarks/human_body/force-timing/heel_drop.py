"""The human body's heel contact under Kinoshita et al. (1993)'s drop test: the share of a 5 kg
mass's impact energy the heel sphere's law absorbs at 0.72 and 0.93 m/s, per dissipation c
[s/m] (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/force-timing/heel_drop.py

The law is the body's own (the heel sphere's stiffness and exponent, F = k·dⁿ·(1 + 1.5·c·ḋ)),
integrated by explicit Euler at 0.1 µs without gravity until the mass leaves; absorbed = 1 −
(v_out/v_in)². Prints one line per c.
"""

from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner.layout import CP_EXP, CP_K

DROP_MASS_KG = 5.0
IMPACT_SPEEDS_MPS = (0.72, 0.93)


def absorbed(k: float, n: float, c: float, v0: float, m: float = DROP_MASS_KG,
             dt: float = 1e-7) -> float:
    """Share of the impact energy [–] the law absorbs when a mass ``m`` [kg] lands at ``v0``
    [m/s]."""
    d, v = 0.0, v0
    while True:
        f = k * max(d, 0.0) ** n * max(1.0 + 1.5 * c * v, 0.0)
        v -= f / m * dt
        d += v * dt
        if d < 0.0:
            return 1.0 - (v / v0) ** 2


def main() -> None:
    heel = runner_from_spec({"model": "able", "body": "human"}).contact_params[0]
    k, n = float(heel[CP_K]), float(heel[CP_EXP])
    print(f"heel sphere: k = {k:.0f} N/m^{n:g}, exponent {n:g}")
    for c in (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0):
        shares = ", ".join(f"{100 * absorbed(k, n, c, v):.0f} % at {v:g} m/s"
                           for v in IMPACT_SPEEDS_MPS)
        print(f"c = {c:g} s/m: {shares}")


if __name__ == "__main__":
    main()
