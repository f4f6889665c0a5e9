"""Blade simulation speed: the numba kernel (one stance, a batch of 20) against MuJoCo.

A 0.25 s stance of the J-shaped built-in blade (one compliant joint) from the synthetic runner;
the kernel at its default step (2e-4 s, BDF2 with sub-steps where the sole slides) and at 1e-4 s;
MuJoCo (the reference engine, contact law applied explicitly) at the largest step it is stable
at, which is already more accurate than the kernel, so the ratio is a lower bound at equal
accuracy. Errors are GRF nRMSE (vertical, horizontal) and distance nRMSE against a converged
kernel run (dt 5e-6 s). The machine is shared: every time is given as wall time and CPU time
(``time.thread_time`` for single-thread runs, ``time.process_time`` for the 2-thread batch),
best of N; the CPU time is the fairer number under load.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from bladelab import units
from bladelab.blade import load_blade
from bladelab.sim import prepare, simulate, simulate_batch
from bladelab.sim.api import run_kernel
from bladelab.sim.synthetic import generate_stance


def _nrmse(a, ref):
    return float(np.sqrt(np.mean((a - ref) ** 2)) / np.ptp(ref))


def _best(fn, repeat, clock=time.thread_time):
    """(min wall, median wall, min CPU) [s] over ``repeat`` calls."""
    wall, cpu = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        c0 = clock()
        fn()
        cpu.append(clock() - c0)
        wall.append(time.perf_counter() - t0)
    return min(wall), float(np.median(wall)), min(cpu)


def _errors(res, ref):
    return (_nrmse(res.grf_z, ref.grf_z), _nrmse(res.grf_x, ref.grf_x),
            _nrmse(res.distance, ref.distance))


def _ms(t):
    return f"{t * 1e3:.3f}"


def run() -> str:
    blade = load_blade("xtreme").build()
    stance, truth = generate_stance(blade, speed_mps=3.6, body_mass_kg=70.0, margin_s=0.06)
    n = int(round(0.25 * stance.sample_rate)) + 1
    stance = type(stance)(**{k: getattr(stance, k)[:n] for k in (
        "time", "clamp_x", "clamp_y", "clamp_z", "clamp_pitch", "grf_x", "grf_y", "grf_z",
        "distance")}, metadata=stance.metadata)
    problem = prepare(blade, stance)  # default step
    fine = prepare(blade, stance, dt=1e-4)
    simulate(problem)  # compile
    ref = simulate(prepare(blade, stance, dt=5e-6, refine=1))
    rows = []
    for label, p in ((f"default dt {problem.dt:.2g} s", problem), (f"dt {fine.dt:.2g} s", fine)):
        res = simulate(p)
        t = _best(lambda p=p: simulate(p), 200)
        rows.append((f"kernel, one stance, {label}", t, _errors(res, ref)))
    t_single = rows[0][1]

    # where the time goes (default step, the bare kernel call)
    c = problem.chain
    K1, D1, K21 = c.stiffness[None], c.damping[None], c.stiffness_quadratic[None]
    no_refine = prepare(blade, stance, refine=1)
    flight = prepare(blade, dataclasses.replace(stance, clamp_z=stance.clamp_z + 1.0))
    split = [
        ("kernel call with energy bookkeeping", problem, True),
        ("kernel call without energy bookkeeping (what batches run)", problem, False),
        ("… and without landing sub-steps (`refine=1`)", no_refine, False),
        ("… clamp 1 m higher, no contact (integrator and outputs only)", flight, False),
    ]
    split_rows = []
    for label, p, energy in split:
        run_kernel(p, K1, D1, K21, with_energy=energy)
        t = _best(lambda p=p, energy=energy: run_kernel(p, K1, D1, K21, with_energy=energy), 200)
        split_rows.append((label, t))

    rng = np.random.default_rng(0)
    K = units.stiffness_per_deg_to_per_rad(rng.uniform(13, 22, (20, 1)))
    D = units.damping_per_deg_to_per_rad(rng.uniform(0.15, 0.5, (20, 1)))
    batch_rows = []
    for par in (False, True):
        simulate_batch(problem, K, D, parallel=par)
        t = _best(lambda par=par: simulate_batch(problem, K, D, parallel=par), 40,
                  clock=time.process_time)
        batch_rows.append(("2 threads (`parallel=True`)" if par else "one thread", t))

    mj_rows = []
    for dt in (None, 2.5e-6):
        mp = prepare(blade, stance, engine="mujoco", **({} if dt is None else {"dt": dt}))
        w0 = time.perf_counter()
        c0 = time.thread_time()
        res = simulate(mp)
        mj_rows.append((mp.dt, time.perf_counter() - w0, time.thread_time() - c0,
                        _errors(res, ref)))
    e_k = rows[0][2]
    mj_default = mj_rows[0]
    equal = [r for r in mj_rows if r[3][0] <= e_k[0] * 1.05 and r[3][1] <= e_k[1] * 1.05]

    lines = [
        "## Blade simulation (`bench_sim.py`)",
        "",
        f"Stance: synthetic runner on `{blade.name}` (one compliant joint), "
        f"{stance.duration:.3f} s at {stance.sample_rate:.0f} Hz, contact "
        f"{truth['contact_time_s'] * 1000:.0f} ms, peak GRF {truth['peak_grf_z_N']:.0f} N. "
        "Errors: nRMSE against the kernel at dt 5e-6 s. Times in ms: wall min / median and CPU "
        "min (thread time; process time for the batch, all threads), best of N.",
        "",
        "| run | wall min / median | CPU min | GRF z nRMSE | GRF x nRMSE | distance nRMSE |",
        "|---|---|---|---|---|---|",
    ]
    for label, (wmin, wmed, cmin), (ez, ex, ed) in rows:
        lines.append(f"| {label} (`simulate`, of 200) | {_ms(wmin)} / {_ms(wmed)} | {_ms(cmin)} | "
                     f"{ez:.3%} | {ex:.3%} | {ed:.4%} |")
    for label, (wmin, wmed, cmin) in batch_rows:
        lines.append(f"| kernel, batch of 20 (K 13–22 N·m/deg, D 0.15–0.5 N·m·s/deg), {label}, "
                     f"of 40 | {wmin * 1e3:.2f} / {wmed * 1e3:.2f} | {cmin * 1e3:.2f} | | | |")
    for dt, wall, cpu, (ez, ex, ed) in mj_rows:
        lines.append(f"| MuJoCo, dt {dt:.2g} s (one run) | {wall * 1e3:.0f} | {cpu * 1e3:.0f} | "
                     f"{ez:.3%} | {ex:.3%} | {ed:.4%} |")
    lines += ["", "Where the time goes (default step, one stance, CPU min of 200):", "",
              "| kernel call | CPU min [ms] |", "|---|---|"]
    for label, (_w, _m, cmin) in split_rows:
        lines.append(f"| {label} | {_ms(cmin)} |")
    ratio_default = mj_default[2] / t_single[2]
    # equal accuracy: the cheapest MuJoCo run whose GRF errors are not above the kernel's
    cheapest = min(equal, key=lambda r: r[2]) if equal else None
    ratio_equal = (f"at equal accuracy (MuJoCo dt {cheapest[0]:.2g} s, itself more accurate) "
                   f"**{cheapest[2] / t_single[2]:.0f}×**" if cheapest else
                   "no MuJoCo step tried reached the kernel's accuracy")
    lines += [
        "",
        f"Kernel vs MuJoCo (CPU time): {ratio_default:.0f}× faster than MuJoCo at its default "
        f"(stability-limited) step {mj_default[0]:.2g} s; {ratio_equal}. Targets: one 0.25 s "
        "stance ≤ 0.5 ms on one core, batch of 20 ≤ 5 ms, ratio ≥ 10×. The 2-core machine is "
        "shared with other jobs (load average about 2 during the run): the CPU minima are the "
        "fairest numbers and all times are upper bounds; the 2-thread batch only gains when the "
        "second core is free.",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    print(run())
