"""Where a collocation stride solve spends its time: a measuring probe (changes nothing in src).

Builds the stride NLPs of a named problem through bladelab's public functions
(``runner_from_spec``, ``build_collocation_model``, ``stride_dynamics``, ``make_guess``,
``StrideNLP``) exactly as ``predict_stride`` does (tracking stage, then the predictive stage
started from its solution), and times variants. One variant per process, so that the peak
memory (``resource.getrusage`` maxrss) belongs to it. Each command prints one JSON record and
appends it to ``--record`` (JSON lines).

Commands (run from the repository root with ``.venv/bin/python``):

``solve``
    One solve, tracking then predictive, each stage with its own Hessian
    (``--tracking-hessian``, ``--predictive-hessian``: limited-memory or exact) and a wall-time
    limit per stage (``--max-wall-s``, IPOPT's ``max_wall_time``). IPOPT's own timing
    statistics (``print_timing_statistics``) are written to a file per stage and parsed:
    seconds inside IPOPT without function evaluations, in function evaluations, and IPOPT's
    split of its own time (factorisation, back solves, quasi-Newton update, ...).
    ``--save-tracking`` keeps the tracking stage's solution vector; ``--from-tracking`` starts
    the predictive stage from such a file (no tracking stage), so that predictive-stage
    variants share one start. ``--ipopt NAME=VALUE`` (repeatable) sets an IPOPT option over
    the library's own for both stages (``mu_strategy``, ``limited_memory_max_history``,
    ``mumps_pivtol``, ``mumps_pivot_order``, ...); the record keeps them.
``evals``
    Time per call of the NLP functions IPOPT calls (objective, gradient, constraints,
    Jacobian, Hessian of the Lagrangian) as the solver builds them: with ``expand`` (SX
    graphs, the library's setting) and without (the MX graphs with ``map``), at one point.
``codegen``
    CasADi code generation of the constraint Jacobian (of the MX graph with ``map``, and/or of
    the expanded SX graph) to C, compiled with gcc at the given -O levels in a temporary
    folder: generation and compile times [s], library size [MB], time per call [ms] and the
    largest relative difference from the interpreted function.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
FUNCS = ("nlp_f", "nlp_grad_f", "nlp_g", "nlp_jac_g", "nlp_hess_l")


def _maxrss_mb() -> float:
    """Peak resident memory of this process so far [MB] (Linux: ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _problem(args):
    """(runner, dynamics, settings, guess on the mesh) of the named problem."""
    from bladelab.predict import defaults
    from bladelab.predict.collocation import build_collocation_model
    from bladelab.predict.collocation.dynamics import stride_dynamics
    from bladelab.predict.collocation.settings import CollocationSettings
    from bladelab.predict.collocation.starting_guess import make_guess
    from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec

    blade = None if args.model == "able" else args.blade
    spec = check_model_spec({"model": args.model, "blade": blade, "body": defaults.BODY})
    runner = runner_from_spec(spec)
    settings = CollocationSettings(mesh_intervals=args.mesh, speed_m_per_s=args.speed)
    dyn = stride_dynamics(build_collocation_model(runner))
    n = settings.mesh_intervals
    g = make_guess(runner, "template", n=n, speed=settings.speed_m_per_s)
    g = g.on_model(runner).resample(n)
    if abs(g.speed - args.speed) > 1e-12 * args.speed:
        g = g.with_speed(args.speed)
    return runner, dyn, settings, g


def _tracking_nlp(runner, dyn, settings, g):
    """The tracking stage's NLP, as ``predict_stride`` builds it."""
    from bladelab.predict.collocation.solve import TRACKING_WEIGHTS
    from bladelab.predict.collocation.transcription import StrideNLP

    grf = None
    if g.vertical_grf_bw is not None and settings.grf_tracking_weight > 0:
        grf = (g.vertical_grf_bw * runner.body_weight, settings.grf_tracking_weight)
    return StrideNLP(dyn, n=settings.mesh_intervals, speed=settings.speed_m_per_s,
                     weights=TRACKING_WEIGHTS, tracking=(g.q, settings.tracking_weight),
                     grf_tracking=grf)


def _predictive_nlp(dyn, settings):
    from bladelab.predict.collocation.transcription import StrideNLP

    return StrideNLP(dyn, n=settings.mesh_intervals, speed=settings.speed_m_per_s,
                     weights=settings.weights)


_IPOPT_LINES = {
    "ipopt_wo_eval_s": r"Total seconds in IPOPT \(w/o function evaluations\)\s*=\s*([\d.eE+-]+)",
    "ipopt_eval_s": r"Total seconds in NLP function evaluations\s*=\s*([\d.eE+-]+)",
    "ipopt_total_s": r"Total seconds in IPOPT\s*=\s*([\d.eE+-]+)",
}


def _parse_ipopt(text: str) -> dict:
    """IPOPT's summary times [s] and its timing statistics (wall seconds per item)."""
    out = {}
    for key, pat in _IPOPT_LINES.items():
        m = re.search(pat, text)
        if m:
            out[key] = float(m.group(1))
    stats = {}
    block = text.split("Timing Statistics:")[-1] if "Timing Statistics:" in text else ""
    for line in block.splitlines():
        m = re.match(r"\s*([A-Za-z][A-Za-z0-9 ()_.-]*?)\s*\.{2,}[^w]*wall:\s*([\d.eE+-]+)", line)
        if m:
            stats[m.group(1).strip()] = float(m.group(2))
    out["ipopt_timing_wall_s"] = stats
    m = re.search(r"Number of objective function evaluations\s*=\s*(\d+)", text)
    if m:
        out["n_eval_f_ipopt"] = int(m.group(1))
    return out


def _ipopt_options(pairs: list[str] | None) -> dict:
    """``NAME=VALUE`` pairs as CasADi IPOPT options (``ipopt.NAME``), over the library's own;
    a value is an int, else a float, else a string."""
    out = {}
    for pair in pairs or []:
        name, _, text = pair.partition("=")
        for kind in (int, float, str):
            try:
                out[f"ipopt.{name.strip()}"] = kind(text.strip())
                break
            except ValueError:
                continue
    return out


def _stage(nlp, x0, stage: str, hessian: str, args) -> tuple[dict, object]:
    """Solve one stage with IPOPT's timing statistics written to a file; the stage's record."""
    log = Path(tempfile.gettempdir()) / f"probe-{os.getpid()}-{stage}.ipopt.txt"
    options = {"ipopt.print_timing_statistics": "yes", "ipopt.output_file": str(log),
               "ipopt.file_print_level": 3, "ipopt.max_wall_time": float(args.max_wall_s)}
    extra = _ipopt_options(args.ipopt)
    options |= extra
    t0 = time.perf_counter()
    sol = nlp.solve(x0, max_iter=args.max_iter, tol=1e-4, hessian=hessian, options=options,
                    speed=args.speed)
    wall = time.perf_counter() - t0
    text = log.read_text() if log.is_file() else ""
    rec = {"stage": stage, "hessian": hessian, "status": sol.status, "success": sol.success,
           "iterations": sol.iterations, "wall_s": wall, "build_s": sol.timings.get("build_s"),
           "solve_s": wall - sol.timings.get("build_s", 0.0), "objective": sol.objective,
           "max_violation": sol.max_violation, "maxrss_mb": _maxrss_mb(),
           "n_vars": nlp.n_vars, "n_cons": nlp.n_cons, "ipopt_options": extra}
    for f in FUNCS:
        key = f.removeprefix("nlp_")
        calls, secs = sol.timings.get(f"calls_{f}", 0.0), sol.timings.get(f"{f}_s", 0.0)
        rec[f"calls_{key}"] = int(calls)
        rec[f"t_{key}_s"] = secs
        rec[f"ms_per_{key}"] = 1e3 * secs / calls if calls else None
    rec["casadi_eval_s"] = sum(rec[f"t_{f.removeprefix('nlp_')}_s"] for f in FUNCS)
    rec.update(_parse_ipopt(text))
    if rec["iterations"] > 0 and "ipopt_wo_eval_s" in rec:
        rec["ms_ipopt_per_iter"] = 1e3 * rec["ipopt_wo_eval_s"] / rec["iterations"]
        rec["ms_total_per_iter"] = 1e3 * rec["solve_s"] / rec["iterations"]
    log.unlink(missing_ok=True)
    return rec, sol


def cmd_solve(args) -> dict:
    import numpy as np

    t0 = time.perf_counter()
    runner, dyn, settings, g = _problem(args)
    rec = {"cmd": "solve", "problem_build_s": time.perf_counter() - t0, "stages": []}
    if args.from_tracking:
        data = np.load(args.from_tracking)
        x0 = data["x"]
        rec["from_tracking"] = str(args.from_tracking)
    else:
        nlp_t = _tracking_nlp(runner, dyn, settings, g)
        st, sol_t = _stage(nlp_t, nlp_t.initial_vector(g), "tracking", args.tracking_hessian,
                           args)
        rec["stages"].append(st)
        print(json.dumps(st), flush=True)
        if not sol_t.success:
            rec["note"] = "tracking stage did not converge; predictive stage not run"
            return rec
        if args.tracking_only:
            return rec
        nlp_p = _predictive_nlp(dyn, settings)
        x0 = nlp_p.initial_vector(sol_t.to_guess("collocation (tracking stage)"))
        if args.save_tracking:
            np.savez(args.save_tracking, x=x0)
    nlp_p = _predictive_nlp(dyn, settings)
    st, _ = _stage(nlp_p, x0, "predictive", args.predictive_hessian, args)
    rec["stages"].append(st)
    rec["total_wall_s"] = time.perf_counter() - t0
    return rec


def _solver_functions(nlp, expand: bool, hessian: str):
    """The IPOPT solver's own oracle functions (objective, gradient, constraints, Jacobian and,
    with the exact Hessian, the Hessian of the Lagrangian), and the solver's build time [s]."""
    import casadi as ca

    opts = {"expand": expand, "ipopt.hessian_approximation": hessian, "print_time": False,
            "ipopt.print_level": 0, "ipopt.sb": "yes"}
    t0 = time.perf_counter()
    solver = ca.nlpsol("probe", "ipopt", nlp.nlp, opts)
    build = time.perf_counter() - t0
    funcs = {}
    for name in FUNCS:
        try:
            funcs[name] = solver.get_function(name)
        except RuntimeError:
            pass
    return solver, funcs, build


def _call_args(func, x, p, lam_g):
    """Numeric inputs by name for an oracle function."""
    import numpy as np

    vals = {"x": x, "p": np.array([p]), "lam_f": np.array([1.0]), "lam_g": lam_g}
    return [vals.get(func.name_in(i), np.zeros(func.size1_in(i)))
            for i in range(func.n_in())]


def _time_call(func, inputs, min_s: float, max_calls: int) -> tuple[float, int, list]:
    """Median time per call [s] over repeated calls (at least 3, about ``min_s`` seconds)."""
    import numpy as np

    out = func(*inputs)
    times = []
    t_all = time.perf_counter()
    while len(times) < 3 or (time.perf_counter() - t_all < min_s and len(times) < max_calls):
        t = time.perf_counter()
        func(*inputs)
        times.append(time.perf_counter() - t)
    return float(np.median(times)), len(times), out


def _point(args, nlp, runner, dyn, settings, g):
    """The evaluation point: the saved tracking solution (``--point``) or the guess."""
    import numpy as np

    if args.point:
        return np.load(args.point)["x"]
    return nlp.initial_vector(g)


def cmd_evals(args) -> dict:
    import numpy as np

    runner, dyn, settings, g = _problem(args)
    stage = args.stage
    nlp = (_tracking_nlp(runner, dyn, settings, g) if stage == "tracking"
           else _predictive_nlp(dyn, settings))
    x = _point(args, nlp, runner, dyn, settings, g)
    rng = np.random.default_rng(0)
    lam_g = rng.standard_normal(nlp.n_cons)
    rec = {"cmd": "evals", "stage": stage, "expand": args.expand, "n_vars": nlp.n_vars,
           "n_cons": nlp.n_cons, "functions": {}}
    _, funcs, build = _solver_functions(nlp, args.expand, "exact")
    rec["solver_build_s"] = build
    for name, f in funcs.items():
        t0 = time.perf_counter()
        inputs = _call_args(f, x, args.speed, lam_g)
        per, calls, out = _time_call(f, inputs, args.min_s, args.max_calls)
        first = time.perf_counter() - t0
        nnz = [int(f.nnz_out(i)) for i in range(f.n_out())]
        rec["functions"][name] = {"ms_per_call": 1e3 * per, "calls": calls, "nnz_out": nnz,
                                  "first_and_timing_s": first,
                                  "sx_nodes": f.n_nodes() if f.is_a("SXFunction") else None,
                                  "class": f.class_name()}
        print(name, json.dumps(rec["functions"][name]), flush=True)
    rec["maxrss_mb"] = _maxrss_mb()
    return rec


def cmd_codegen(args) -> dict:
    import casadi as ca
    import numpy as np

    runner, dyn, settings, g = _problem(args)
    nlp = _predictive_nlp(dyn, settings)
    x = _point(args, nlp, runner, dyn, settings, g)
    rec = {"cmd": "codegen", "n_vars": nlp.n_vars, "n_cons": nlp.n_cons, "variants": []}
    work = Path(tempfile.mkdtemp(prefix="probe-codegen-"))
    rec["folder"] = str(work)
    for graph in args.graphs:
        _, funcs, _ = _solver_functions(nlp, graph == "sx", "limited-memory")
        jac = funcs["nlp_jac_g"]
        inputs = _call_args(jac, x, args.speed, None)
        ref_ms, _, ref = _time_call(jac, inputs, args.min_s, args.max_calls)
        ref_nz = np.concatenate([np.asarray(ca.DM(o).nonzeros()) for o in ref])
        name = f"jac_{graph}"
        t0 = time.perf_counter()
        cg = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        cg.add(jac)
        cg.generate(str(work) + "/")
        gen_s = time.perf_counter() - t0
        src = work / f"{name}.c"
        base = {"graph": graph, "interpreted_ms_per_call": 1e3 * ref_ms, "generate_s": gen_s,
                "c_mb": src.stat().st_size / 1e6}
        for opt in args.opt:
            lib = work / f"{name}_{opt}.so"
            t0 = time.perf_counter()
            try:
                subprocess.run(["gcc", f"-{opt}", "-shared", "-fPIC", "-o", str(lib), str(src),
                                "-lm"], check=True, timeout=args.compile_timeout_s,
                               capture_output=True)
            except subprocess.TimeoutExpired:
                row = base | {"opt": opt, "compile_s": None,
                              "note": f"compile stopped at {args.compile_timeout_s} s"}
                rec["variants"].append(row)
                print(json.dumps(row), flush=True)
                continue
            comp = time.perf_counter() - t0
            ext = ca.external(jac.name(), str(lib))
            per, calls, out = _time_call(ext, inputs, args.min_s, args.max_calls)
            nz = np.concatenate([np.asarray(ca.DM(o).nonzeros()) for o in out])
            rel = float(np.max(np.abs(nz - ref_nz)) / max(np.max(np.abs(ref_nz)), 1e-300))
            row = base | {"opt": opt, "compile_s": comp, "so_mb": lib.stat().st_size / 1e6,
                          "compiled_ms_per_call": 1e3 * per, "calls": calls,
                          "max_rel_diff": rel}
            rec["variants"].append(row)
            print(json.dumps(row), flush=True)
    rec["maxrss_mb"] = _maxrss_mb()
    return rec


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("command", choices=("solve", "evals", "codegen"))
    p.add_argument("--model", default="amputee", choices=("able", "amputee", "transfemoral"))
    p.add_argument("--blade", default="Cat6")
    p.add_argument("--speed", type=float, default=4.0, help="prescribed speed [m/s]")
    p.add_argument("--mesh", type=int, default=50, help="mesh intervals")
    p.add_argument("--tracking-hessian", default="limited-memory")
    p.add_argument("--predictive-hessian", default="limited-memory")
    p.add_argument("--max-iter", type=int, default=3000)
    p.add_argument("--max-wall-s", type=float, default=600.0,
                   help="IPOPT's wall-time limit per stage [s]")
    p.add_argument("--save-tracking", type=Path)
    p.add_argument("--from-tracking", type=Path)
    p.add_argument("--ipopt", action="append", metavar="NAME=VALUE",
                   help="an IPOPT option for the solves, over the library's (repeatable)")
    p.add_argument("--tracking-only", action="store_true", help="solve the tracking stage only")
    p.add_argument("--stage", default="predictive", choices=("tracking", "predictive"))
    p.add_argument("--expand", action=argparse.BooleanOptionalAction, default=True)
    p.add_argument("--point", type=Path, help="evaluation point: a --save-tracking file")
    p.add_argument("--min-s", type=float, default=3.0, help="timing seconds per function")
    p.add_argument("--max-calls", type=int, default=200)
    p.add_argument("--graphs", nargs="+", default=["mx", "sx"], choices=("mx", "sx"))
    p.add_argument("--opt", nargs="+", default=["O1", "O2"])
    p.add_argument("--compile-timeout-s", type=float, default=300.0)
    p.add_argument("--label", default="")
    p.add_argument("--record", type=Path, default=HERE / "records.jsonl")
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    rec = {"cmd_solve": cmd_solve, "cmd_evals": cmd_evals,
           "cmd_codegen": cmd_codegen}[f"cmd_{args.command}"](args)
    import casadi as ca

    rec |= {"label": args.label, "argv": " ".join(sys.argv[1:]), "model": args.model,
            "blade": None if args.model == "able" else args.blade, "speed_m_per_s": args.speed,
            "mesh": args.mesh, "process_wall_s": time.perf_counter() - t0,
            "maxrss_mb": _maxrss_mb(), "casadi": ca.__version__,
            "date": time.strftime("%Y-%m-%d %H:%M")}
    line = json.dumps(rec)
    print(line, flush=True)
    with open(args.record, "a") as fh:
        fh.write(line + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
