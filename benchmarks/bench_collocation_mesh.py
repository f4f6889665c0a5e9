"""Collocation convergence: the mesh-halving check of the shipped strides, on one core.

The shipped amputee Cat6 stride at 4 m/s and the shipped able stride at 3.5 m/s (the human
body, people's joint angles at the default weight, mesh 50), each solved again on 100
intervals from itself (``bladelab.predict.collocation.mesh_check.check_mesh``, as
``bladelab predict --mesh-check`` does). Reported per stride: the change of the objective, the
stride time, the cost of transport and each leg's peak, the verdict (settled: objective and
stride time within 1 %), the round trip (the stride's mesh again, from the finer stride:
its objective against the stride's, and the mesh's own part, the finer stride against it), and
the finer solve's iterations, wall time (of it, IPOPT's own) and the process's peak memory. The target is the project's settling criterion; the measured
answers of the category study are in benchmarks/human_body/categories-people10/mesh-100.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: MUMPS/BLAS single-threaded

STRIDES = (("amputee", "Cat6", 4.0), ("able", None, 3.5))
MESH = 50


def _pct(check, key: str) -> str:
    return _signed(check.change_pct(key))


def _signed(value) -> str:
    return "–" if value is None else f"{value:+.2f} %"


def run() -> str:
    from bladelab.predict.collocation.mesh_check import check_mesh, round_trip, with_round_trip
    from bladelab.predict.collocation.settings import CollocationSettings, people_settings
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.predict.collocation.starting_guess import make_guess
    from bladelab.runner import build_runner

    people = people_settings("human")  # as the command line solves the able and amputee runners
    rows = []
    for model, blade, speed in STRIDES:
        spec = {"model": model, "blade": blade, "body": "human"}
        runner = build_runner(model, blade=blade, body="human")
        settings = CollocationSettings(mesh_intervals=MESH, speed_m_per_s=speed, **people)
        stride = predict_stride(runner, settings,
                                make_guess(runner, "stored", n=MESH, speed=speed),
                                model_spec=spec)
        fine, check = check_mesh(runner, stride)
        check = with_round_trip(check, round_trip(runner, stride, fine))
        trip = {k: check.round_trip_pct(k) for k in ("objective", "stride_time_s")}
        legs = stride.leg_names
        t = fine.nlp.timings
        rows.append(
            f"| {model}{' ' + blade if blade else ''}, {speed:g} m/s | "
            f"{_pct(check, 'objective')} | {_pct(check, 'stride_time_s')} | "
            f"{_pct(check, 'cost_of_transport_J_per_kg_m')} | "
            + " / ".join(_pct(check, f"peak_vertical_grf_{leg}_bw") for leg in legs)
            + f" | {'settled' if check.settled else 'not settled'} | "
            f"{_signed(trip['objective'][0])} | {_signed(trip['objective'][1])} / "
            f"{_signed(trip['stride_time_s'][1])} | {fine.nlp.iterations} | "
            f"{fine.nlp.wall_s:.0f} s ({t.get('ipopt_own_s', 0.0):.0f} s) | "
            f"{t.get('peak_memory_MB', float('nan')):.0f} MB |")
    return "\n".join([
        "## Collocation: the mesh-halving check of the shipped strides",
        "",
        f"Each shipped stride (human body, mesh {MESH}, people's angles at the default weight) "
        f"solved again on {2 * MESH} intervals from itself, IPOPT warm-started (barrier 1e-4, "
        "bound push 1e-8) "
        "(`bladelab predict --mesh-check`); settled: objective and stride time within 1 %. "
        f"Round trip: the {MESH}-interval problem solved again from the finer stride; its "
        "objective against the stride's (below 0: a lower optimum of the stride's own mesh), "
        "and the mesh's own part (the finer stride against the round trip's) in objective and "
        "stride time.",
        "",
        "| stride | objective | stride time | cost of transport | peaks per leg | verdict | "
        "round trip: objective | the mesh's own part: objective / stride time | "
        "iterations | wall (of it, IPOPT's own) | peak memory |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
    ])
