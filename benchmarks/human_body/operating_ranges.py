"""Fit the leg muscles' tendon slack lengths to people's moment–angle curves (a probe).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/operating_ranges.py [--hip-tests-knee DEG]
        [--kind able] [--keep MUSCLES] [--muscle JSON]

The curves and their comparison: :mod:`bladelab.runner.strength` (Anderson et al. 2007, the
shape of each exertion's active moment–angle curve). The unknowns are the tendon slack lengths
of the nine leg muscles, as factors of the body's (bounds 0.7–1.3), least squares over the six
exertions with a small pull (0.1 per 10 % change) toward the body's. ``--hip-tests-knee``
moves the knee of the hip exertions' posture [deg of flexion] (default: the module's 90°), to see
how far the fit depends on the assumed postures; ``--keep`` names muscles whose lengths stay
(e.g. ``hamstrings``, whose length the passive moments also set). Prints the model's and people's normalised
curves before and after, the fitted lengths [m] and factors, and each exertion's peak moment
[N·m] beside people's.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math

import numpy as np
from scipy.optimize import least_squares

from bladelab.runner import build_runner
from bladelab.runner.geometry import LEG_MUSCLES
from bladelab.runner.muscle import MP_LTS
from bladelab.runner.strength import (
    ANDERSON_2007,
    EXERTIONS,
    active_moments,
    exertion_geometry,
    people_moments,
)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--hip-tests-knee", type=float, default=None)
    ap.add_argument("--kind", default="able")
    ap.add_argument("--keep", default="", help="muscles whose length stays, comma-separated")
    ap.add_argument("--muscle", default=None,
                    help='JSON {muscle type: {field: value}} changed before the fit, e.g. '
                         '\'{"soleus": {"tendon_strain_at_fmax": 0.1}}\'')
    args = ap.parse_args()
    if args.muscle:
        from bladelab.runner.params import default_runner_params, runner_params_from_dict

        data = json.loads(default_runner_params(args.kind, body="human").model_dump_json())
        for muscle, row in json.loads(args.muscle).items():
            data["muscle_types"][muscle].update(row)
        runner = build_runner(runner_params_from_dict(data))
    else:
        runner = build_runner(args.kind, body="human")
    athlete = runner.params.athlete
    ex = dict(EXERTIONS)
    for name in ("hip extension", "hip flexion"):
        if args.hip_tests_knee is not None:
            ex[name] = dataclasses.replace(ex[name],
                                           posture_deg={"knee_angle": -args.hip_tests_knee})
    geo = {k: exertion_geometry(runner, e) for k, e in ex.items()}
    rows = geo["hip extension"][0]
    mp0 = np.asarray(runner.muscle_params)[rows].copy()
    people = {k: people_moments(k, e.angles_deg, body_mass_kg=athlete.body_mass_kg,
                                height_m=athlete.height_m) for k, e in ex.items()}

    keep = [LEG_MUSCLES.index(m) for m in args.keep.split(",") if m]

    def curves(factors):
        factors = np.array(factors, float)
        factors[keep] = 1.0
        mp = mp0.copy()
        mp[:, MP_LTS] *= factors
        return {k: active_moments(mp, geo[k][1], geo[k][2], e.moment_sign)
                for k, e in ex.items()}

    def residuals(log_f):
        c = curves(np.exp(log_f))
        r = [c[k] / max(c[k].max(), 1e-6) - people[k] / people[k].max() for k in ex]
        return np.concatenate(r + [log_f / math.log(1.1) * 0.1])

    def show(label, factors):
        c = curves(factors)
        print(f"== {label}")
        for k, e in ex.items():
            m, p = c[k] / c[k].max(), people[k] / people[k].max()
            angles = np.asarray(e.angles_deg)
            print(f"  {k:15s} peak {c[k].max():5.0f} N·m at {angles[np.argmax(c[k])]:4.0f}° "
                  f"(people {people[k].max():4.0f} N·m at "
                  f"{math.degrees(ANDERSON_2007[k][2]):4.0f}°), "
                  f"RMS of the normalised difference {np.sqrt(np.mean((m - p) ** 2)):.3f}")
            print("    deg    " + " ".join(f"{a:5.0f}" for a in angles[::2]))
            print("    model  " + " ".join(f"{v:5.2f}" for v in m[::2]))
            print("    people " + " ".join(f"{v:5.2f}" for v in p[::2]))

    n = len(rows)
    show("the body", np.ones(n))
    fit = least_squares(residuals, np.zeros(n), diff_step=1e-3,
                        bounds=(np.full(n, math.log(0.7)), np.full(n, math.log(1.3))))
    factors = np.exp(fit.x)
    factors[keep] = 1.0
    show("fitted", factors)
    print(json.dumps({m: round(float(mp0[i, MP_LTS] * factors[i]), 4)
                      for i, m in enumerate(LEG_MUSCLES)}))
    print(json.dumps({m: round(float(factors[i]), 3) for i, m in enumerate(LEG_MUSCLES)}))


if __name__ == "__main__":
    main()
