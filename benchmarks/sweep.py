"""Benchmark: ``pfaff.sweep`` of 256 pendulum runs on 1 and 2 Dask workers against one plain process.

The model is a pendulum in its angle (a particle of mass m at (L sin θ, −L cos θ), potential
−m g L cos θ), written as a model file; the grid is 16 lengths L ∈ [0.5, 2] × 16 release angles
θ₀ ∈ [0.1, 1.5] (256 runs), each over ``--t-end`` (default 10 s, about 5 to 11 periods) with the
default tolerances and 201 samples.

Rows (wall-clock seconds, the best of ``--repeat``):

``plain process``
    The baseline: one process, a plain loop of ``pfaff.simulate`` over the grid on one model
    compiled once (``NumericModel.with_parameters`` per run), nothing of Dask.
``plain, compile per run``
    The same loop deriving and compiling the model file's equations again for every run
    (``ModelFile.compile(L=...)``, the fused code from the on-disk cache): what a loop without
    ``with_parameters`` costs.
``synchronous``
    ``pfaff.sweep(..., scheduler="synchronous")``: the sweep's own code in this process (warm: the
    model file compiled by a first call).
``dask, N workers``
    ``pfaff.sweep`` on a local cluster of N single-threaded worker processes, started before the
    timing (its start-up is printed apart) and warm (pfaff imported, the model compiled once per
    worker by a first sweep, as a second sweep on a running cluster would find it).

The speed-up is the plain process's time over the row's; ``run s`` is the sum of the runs' own
wall times (inside the workers for the Dask rows): well above the plain row's, the runs were
slowed down by sharing the cores (other processes), not by Dask. Each result is checked equal to the
plain loop's (same q at every sample to 1e-12) before it is timed. The machine's load average is
printed: other processes on the same cores make the Dask rows slower, not the plain one alone.

Run (from the project root)::

    python benchmarks/sweep.py                  # 256 runs of 10 s
    python benchmarks/sweep.py --quick          # 64 runs of 2 s
    python benchmarks/sweep.py --json           # the rows as JSON on stdout
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import pfaff

PENDULUM = """
[model]
name = "pendulum"
coordinates = ["theta"]
parameters = { m = 1.0, L = 1.0, g = 9.81 }
potential = "-m*g*L*cos(theta)"

[[particles]]
mass = "m"
position = ["L*sin(theta)", "-L*cos(theta)"]

[initial]
q = { theta = 0.5 }

[simulate]
t_end = {t_end}
"""


def plain_loop(path: Path, vary: dict, t_end: float, per_run_compile: bool) -> np.ndarray:
    """q of every run, shape (runs, samples, 1): the baseline loop in this process."""
    mf = pfaff.load_model(path)
    t_eval = np.linspace(0, t_end, 201)
    model = mf.compile()
    out = []
    for L in vary["L"]:
        for th in vary["q0.theta"]:
            m = mf.compile(L=L) if per_run_compile else model.with_parameters({"L": L})
            traj = pfaff.simulate(m, [th], [0.0], (0, t_end), t_eval=t_eval, progress=False)
            assert traj.success, traj.message
            out.append(traj.q)
    return np.array(out)


def best(fn, repeat: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return min(times), result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=16, help="values per axis (runs = n², default 16)")
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--quick", action="store_true", help="64 runs of 2 s")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.n, args.t_end, args.repeat = 8, 2.0, 1
    from distributed import LocalCluster

    folder = Path(tempfile.mkdtemp(prefix="pfaff-bench-sweep-"))
    path = folder / "pendulum.toml"
    path.write_text(PENDULUM.replace("{t_end}", repr(args.t_end)))
    vary = {"L": np.linspace(0.5, 2.0, args.n), "q0.theta": np.linspace(0.1, 1.5, args.n)}
    runs = args.n**2
    rows = []
    plain_loop(path, vary, args.t_end, False)  # warm: imports, code cache, machine code
    t_plain, ref = best(lambda: plain_loop(path, vary, args.t_end, False), args.repeat)
    rows.append(("plain process", 1, t_plain, t_plain))
    t_naive, q = best(lambda: plain_loop(path, vary, args.t_end, True), 1)
    np.testing.assert_allclose(q, ref, rtol=0, atol=1e-12)
    rows.append(("plain, compile per run", 1, t_naive, t_naive))

    def check(ds) -> None:
        assert int(ds.attrs["failed"]) == 0
        np.testing.assert_allclose(ds.q.values.reshape(ref.shape), ref, rtol=0, atol=1e-12)

    pfaff.sweep(path, vary, scheduler="synchronous")  # warm: the model compiled in this process
    t_sync, ds = best(lambda: pfaff.sweep(path, vary, scheduler="synchronous"), args.repeat)
    check(ds)
    rows.append(("synchronous", 1, t_sync, float(ds.seconds.sum())))
    starts = {}
    for n in args.workers:
        start = time.perf_counter()
        cluster = LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
            silence_logs=logging.ERROR,
        )  # fmt: skip
        starts[n] = time.perf_counter() - start
        try:
            address = cluster.scheduler_address

            def on_cluster(address: str = address) -> object:
                return pfaff.sweep(path, vary, scheduler=address, progress=False)

            check(on_cluster())  # warm: the workers import pfaff and compile the model
            t, ds = best(on_cluster, args.repeat)
            check(ds)
            mode = f"dask, {n} worker{'s' * (n > 1)} (batch {ds.attrs['batch']})"
            rows.append((mode, n, t, float(ds.seconds.sum())))
        finally:
            cluster.close()
    report(rows, runs, args, t_plain, starts)


def report(rows: list, runs: int, args: argparse.Namespace, t_plain: float, starts: dict) -> None:
    load = os.getloadavg()
    head = (
        f"pfaff.sweep: {runs} pendulum runs of {args.t_end:g} s, 201 samples each; "
        f"{os.cpu_count()} CPUs, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} "
        f"(Python {platform.python_version()})"
    )
    out = [
        {"mode": m, "workers": w, "seconds": t, "run_seconds": r, "runs_per_second": runs / t,
         "speedup": t_plain / t}
        for m, w, t, r in rows
    ]  # fmt: skip
    if args.json:
        print(json.dumps({"runs": runs, "t_end": args.t_end, "load": load, "rows": out,
                          "cluster_start_seconds": starts}))  # fmt: skip
        return
    print(head)
    print(f"{'mode':<34} {'workers':>7} {'wall s':>8} {'run s':>8} {'runs/s':>8} {'speed-up':>9}")
    for r in out:
        print(
            f"{r['mode']:<34} {r['workers']:>7} {r['seconds']:>8.2f} {r['run_seconds']:>8.2f} "
            f"{r['runs_per_second']:>8.1f} {r['speedup']:>8.2f}x"
        )
    for n, s in starts.items():
        print(f"local cluster of {n} worker(s): started in {s:.1f} s (not in the rows)")


if __name__ == "__main__":
    sys.exit(main())
