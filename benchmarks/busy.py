"""Benchmark: small dense solves on a busy machine, default BLAS threads against one (issue 21).

Two ``python -c "while 1: pass"`` processes load the machine while the rows are measured
(``--no-load`` leaves them out); they are killed at the end, on Ctrl-C and on errors too. Every variant runs in a
fresh subprocess whose BLAS thread count is fixed by its environment before NumPy is imported
(``single``: ``OPENBLAS_NUM_THREADS`` = ``OMP_NUM_THREADS`` = ``MKL_NUM_THREADS`` = 1; ``default``:
the three removed, so OpenBLAS starts one thread per core). The two variants of a row alternate,
``--pairs`` times (default 7; the first of a pair alternates as well), and the table gives the
medians over the pairs of the wall and CPU (``time.process_time``, all threads of the process)
seconds measured inside the subprocess: imports, model build, compilation and a warm-up are left
out.

Rows (the ratio is variant / baseline; the target bounds the wall-time ratio):

``bicycle accelerations``
    ``model.accelerations(t, q, q̇)`` of :func:`pfaff.models.whipple_bicycle` (Meijaard's values, a
    consistent leaning, steered state at 4 m/s), ms per call: the median of ``--repeat`` loops of
    ``--calls`` calls after a warm-up. Default threads against single (baseline). Target ≤ 1.3.
``arm, PD through inputs``
    5 s of a planar 3-link arm (point masses at the ends of massless links, relative joint angles
    q1, q2, q3, gravity along −y) driven to a set point by the PD law
    τ_i = −k_p (q_i − r_i) − k_d q̇_i written as three feedback inputs u_i(t, q, q̇) (``System.add_input``,
    ``simulate(..., inputs={"u1": law, ...})``), seconds per run. Default threads against single
    (baseline). Target ≤ 1.3.
``arm, inputs vs PD in the model``
    The same arm with the same law written into the model (τ_i an expression of q_i, q̇_i with
    parameters kp, kd, r_i, no inputs) as the baseline, against the inputs version; both single.
    Target ≤ 1.5. The two must end in the same state: the largest |Δq|, |Δq̇| at t = 5 s is printed.

Run (from the project root)::

    python benchmarks/busy.py                       # 7 pairs per row, under load
    python benchmarks/busy.py --pairs 3 --no-load   # quick, on an idle machine
    python benchmarks/busy.py --pfaff-src ../other/src   # time another checkout's pfaff

``--pfaff-src PATH`` is put first on the subprocesses' ``PYTHONPATH``; the table's header says which
``pfaff/__init__.py`` they imported.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import time

THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
ARM = {"m1": 1.0, "m2": 0.8, "m3": 0.5, "l1": 0.6, "l2": 0.5, "l3": 0.3, "g": 9.81}
PD = {"kp": 40.0, "kd": 6.0, "r1": 1.2, "r2": -0.6, "r3": 0.4}
ARM_T_END = 5.0


# ------------------------------------------------------------------------------ models
def planar_arm(*, feedback: bool):
    """A planar 3-link arm in relative joint angles, driven by a PD law on every joint.

    Link i (length l_i, massless) carries a point mass m_i at its end; the absolute angle of link
    i from the downward vertical is q1 + … + qi. With ``feedback`` the joint torques are the inputs
    u1, u2, u3 (``System.add_input``); without it they are the PD law itself,
    τ_i = −kp (q_i − r_i) − kd q̇_i, with kp, kd, r_i parameters.
    """
    import sympy as sp

    import pfaff

    q = pfaff.coordinates("q1 q2 q3")
    m, length = sp.symbols("m1:4"), sp.symbols("l1:4")
    g, kp, kd = sp.symbols("g kp kd")
    arm = pfaff.System(list(q), name="planar 3-link arm")
    x = y = sp.S.Zero
    angle = sp.S.Zero
    for i in range(3):
        angle += q[i]
        x, y = x + length[i] * sp.sin(angle), y - length[i] * sp.cos(angle)
        arm.add_particle(m[i], [x, y], name=f"mass {i + 1}")
        arm.add_potential_energy(m[i] * g * y, name=f"gravity {i + 1}")
    for i in range(3):
        if feedback:
            tau = arm.add_input(f"u{i + 1}")
        else:
            tau = -kp * (q[i] - sp.Symbol(f"r{i + 1}")) - kd * q[i].diff(pfaff.t)
        arm.add_generalized_force(q[i], tau, name=f"joint {i + 1}")
    return arm


def pd_law(i: int):
    """The PD law of joint ``i`` as a feedback input u(t, q, q̇)."""
    kp, kd, r = PD["kp"], PD["kd"], PD[f"r{i + 1}"]
    return lambda t, q, qd: -kp * (q[i] - r) - kd * qd[i]


# ------------------------------------------------------------------------------ one variant
def _timed(fn) -> tuple[float, float, object]:
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w0, time.process_time() - c0, out


def measure_bicycle(calls: int, repeat: int) -> dict:
    """ms of wall and CPU time per ``accelerations`` call, medians of ``repeat`` loops."""
    import numpy as np

    import pfaff
    from pfaff.models.bicycle import bicycle_state

    model = pfaff.models.whipple_bicycle().equations().compile(pfaff.models.MEIJAARD)
    q, qd = bicycle_state(pfaff.models.MEIJAARD, phi=0.1, delta=0.2, phi_dot=0.3, speed=4.0)
    for _ in range(max(calls // 4, 10)):  # warm-up
        model.accelerations(0.0, q, qd)

    def loop() -> None:
        for _ in range(calls):
            model.accelerations(0.0, q, qd)

    runs = [_timed(loop) for _ in range(repeat)]
    qdd, _ = model.accelerations(0.0, q, qd)
    return {
        "wall": statistics.median(w for w, _, _ in runs) / calls * 1e3,
        "cpu": statistics.median(c for _, c, _ in runs) / calls * 1e3,
        "unit": "ms/call",
        "state": np.asarray(qdd).tolist(),
    }


def measure_arm(feedback: bool) -> dict:
    """Seconds of wall and CPU time of one 5 s run (after a 0.2 s warm-up run)."""
    import numpy as np

    import pfaff

    values = ARM if feedback else ARM | PD
    model = planar_arm(feedback=feedback).equations().compile(values)
    kw = {"inputs": {f"u{i + 1}": pd_law(i) for i in range(3)}} if feedback else {}
    q0, qd0 = np.array([0.3, 0.2, -0.1]), np.zeros(3)

    def run(t_end: float):
        return pfaff.simulate(model, q0, qd0, (0.0, t_end), progress=False, **kw)

    run(0.2)  # warm-up: machine code, lazy imports
    wall, cpu, traj = _timed(lambda: run(ARM_T_END))
    if not traj.success:
        raise RuntimeError(f"the arm run failed: {traj.message}")
    return {
        "wall": wall,
        "cpu": cpu,
        "unit": "s/run",
        "nfev": int(traj.stats["nfev"]),
        "state": np.concatenate([traj.q[-1], traj.qd[-1]]).tolist(),
    }


def measure(row: str, variant: str, calls: int, repeat: int) -> dict:
    import pfaff

    if row == "bicycle":
        out = measure_bicycle(calls, repeat)
    else:
        out = measure_arm(feedback=variant != "model")
    return out | {"pfaff": pfaff.__file__}


# ------------------------------------------------------------------------------ the parent
ROWS = {
    # row: (label, baseline variant, other variant, target of other/baseline)
    "bicycle": ("bicycle accelerations", "single", "default", 1.3),
    "arm-threads": ("arm, PD through inputs", "single", "default", 1.3),
    "arm-inputs": ("arm, inputs vs PD in the model", "model", "inputs", 1.5),
}


def _env(variant: str, pfaff_src: str | None) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARS}
    if variant != "default":  # single threads; "model" and "inputs" are single-threaded too
        env |= {k: "1" for k in THREAD_VARS}
    if pfaff_src:
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [pfaff_src, env.get("PYTHONPATH")]))
    return env


def run_variant(row: str, variant: str, args: argparse.Namespace) -> dict:
    measured = "bicycle" if row == "bicycle" else "arm"
    cmd = [sys.executable, __file__, "--measure", measured, variant]
    cmd += ["--calls", str(args.calls), "--repeat", str(args.repeat)]
    done = subprocess.run(
        cmd, capture_output=True, text=True, env=_env(variant, args.pfaff_src), check=False
    )
    if done.returncode:
        raise RuntimeError(f"{row}/{variant} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def start_load(n: int, procs: list[subprocess.Popen]) -> None:
    """Start ``n`` busy loops, appended to ``procs`` one by one (so a failure leaks none)."""
    for _ in range(n):
        procs.append(subprocess.Popen([sys.executable, "-c", "while 1: pass"]))


def stop_load(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        p.kill()
    for p in procs:
        p.wait()


def measure_row(row: str, args: argparse.Namespace) -> dict:
    _, base, other = ROWS[row][:3]
    runs: dict[str, list[dict]] = {base: [], other: []}
    for i in range(args.pairs):
        order = (base, other) if i % 2 == 0 else (other, base)
        for variant in order:
            runs[variant].append(run_variant(row, variant, args))
        print(f"  {row}: pair {i + 1}/{args.pairs} done", file=sys.stderr, flush=True)
    return runs


def _median(runs: list[dict], key: str) -> float:
    return statistics.median(r[key] for r in runs)


def print_table(results: dict, args: argparse.Namespace, load: int) -> bool:
    some = next(iter(next(iter(results.values())).values()))[0]
    print(
        f"Small dense solves on a busy machine: load {'ON' if load else 'OFF'} ({load} busy-loop "
        f"processes on {os.cpu_count()} cores), {args.pairs} interleaved pairs per row, medians"
    )
    print(f"pfaff imported by the subprocesses: {some['pfaff']}")
    print("baseline = the first variant of a row; ratio = variant / baseline; target on wall\n")
    head = (
        f"{'row':32} {'baseline':>9} {'variant':>9} {'unit':>8} {'wall base':>10} {'wall var':>10} "
        f"{'ratio':>7} {'cpu base':>10} {'cpu var':>10} {'ratio':>7} {'target':>7}  verdict"
    )
    print(head)
    print("-" * len(head))
    ok = True
    for row, runs in results.items():
        label, base, other, target = ROWS[row]
        b, o = runs[base], runs[other]
        wb, cb, wo, co = (
            _median(b, "wall"),
            _median(b, "cpu"),
            _median(o, "wall"),
            _median(o, "cpu"),
        )
        passed = wo / wb <= target
        ok &= passed
        print(
            f"{label:32} {base:>9} {other:>9} {b[0]['unit']:>8} {wb:10.4g} {wo:10.4g} "
            f"{wo / wb:7.2f} {cb:10.4g} {co:10.4g} {co / cb:7.2f} {'≤' + str(target):>7}  "
            f"{'PASS' if passed else 'FAIL'}"
        )
    print()
    for row, runs in results.items():
        if row == "bicycle":
            continue
        _, base, other, _ = ROWS[row]
        for variant in (base, other):
            nfev = _median(runs[variant], "nfev")
            ms = 1e3 * _median(runs[variant], "wall") / nfev
            print(f"{row} / {variant}: {nfev:.0f} right-hand sides, {ms:.3f} ms wall per rhs")
    for row in results:
        states = [r["state"] for rs in results[row].values() for r in rs]
        spread = max(max(abs(a - b) for a, b in zip(s, states[0], strict=True)) for s in states)
        what = "q̈" if row == "bicycle" else "final (q, q̇) at t = 5 s"
        print(f"{row}: max difference of {what} between all runs: {spread:.1e}")
    return ok


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=7, help="interleaved pairs per row (default 7)")
    ap.add_argument("--calls", type=int, default=200, help="bicycle: calls per timed loop")
    ap.add_argument("--repeat", type=int, default=5, help="bicycle: timed loops (median)")
    ap.add_argument("--load", type=int, default=2, help="busy-loop processes (default 2)")
    ap.add_argument("--no-load", action="store_true", help="no busy-loop processes")
    ap.add_argument("--rows", nargs="+", choices=list(ROWS), default=list(ROWS))
    ap.add_argument("--pfaff-src", help="PYTHONPATH of the subprocesses (a checkout's src/)")
    ap.add_argument("--measure", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.measure:
        row, variant = args.measure
        print(json.dumps(measure(row, variant, args.calls, args.repeat)))
        return
    load = 0 if args.no_load else args.load
    before = os.getloadavg()[0]
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # so that `finally` runs
    signal.signal(signal.SIGINT, signal.default_int_handler)  # even if started with it ignored
    procs: list[subprocess.Popen] = []
    try:
        start_load(load, procs)
        results = {row: measure_row(row, args) for row in args.rows}
        after = os.getloadavg()[0]
    finally:
        stop_load(procs)
    ok = print_table(results, args, load)
    print(f"1-minute load average: {before:.2f} before the load, {after:.2f} at the end")
    if not ok:
        sys.exit(1)


if __name__ == "__main__":
    main()
