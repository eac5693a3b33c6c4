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

``ship`` (a second table; ``--ship-links 0`` leaves it out)
    A sweep of a chain of ``--ship-links`` (default 7) pendulum links in absolute angles (a model
    file whose derivation and compilation cost about a second; n = 7: the generated Python; at
    n = 8 machine code, which the pickle carries made, with the compiled loop's) on a
    fresh local cluster of 2 workers, ``--ship-n``² runs of 2 s, in two modes: ``shipped`` (the
    default: the spec carries the compiled model pickled by
    :func:`pfaff.sweep.source.shipped_model`, each worker unpickles it) and ``derived in workers``
    (``shipped_model`` patched to return None: each worker derives and compiles the file itself).
    ``cold s`` is the wall time of the first sweep on a fresh cluster (the driver's own derivation
    and compilation included for ``shipped``), ``warm s`` a second sweep on the same cluster; the
    per-worker setup (unpickle, or derive + compile; then one ``accelerations`` call) is timed
    inside each worker of another fresh cluster, as the first thing it does; ``driver s`` is
    ``shipped_model`` alone (SymPy's cache cleared). Both with pfaff's on-disk code cache on (a
    file swept before on this machine) and off (``PFAFF_CACHE=0`` for the driver and the workers:
    a new file, or workers on other machines). The modes alternate ``--ship-repeat`` times
    (default 3) and the table gives medians.

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
import importlib
import json
import logging
import os
import pickle
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import pfaff

source = importlib.import_module("pfaff.sweep.source")  # (pfaff.sweep is the function)

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
    ap.add_argument("--ship-links", type=int, default=7, help="chain of the ship table (0: none)")
    ap.add_argument("--ship-n", type=int, default=4, help="ship table: values per axis (n²)")
    ap.add_argument("--ship-repeat", type=int, default=3, help="ship table: alternations")
    ap.add_argument("--ship-only", action="store_true", help="only the ship table")
    args = ap.parse_args()
    if args.quick:
        args.n, args.t_end, args.repeat = 8, 2.0, 1
    from distributed import LocalCluster

    if args.ship_only:
        ship_table(args.ship_links, args.ship_n, args.ship_repeat)
        return

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
    if args.ship_links and not args.json:
        print()
        ship_table(args.ship_links, args.ship_n, args.ship_repeat)


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


# ------------------------------------------------------------------ the shipped compiled model
def chain_file(links: int) -> str:
    """A model file: ``links`` point masses m on massless links of length l, absolute angles,
    gravity g."""
    names = [f"th{i}" for i in range(1, links + 1)]
    text = [
        "[model]",
        f'name = "{links}-link chain"',
        "coordinates = [" + ", ".join(f'"{c}"' for c in names) + "]",
        "parameters = { m = 1.0, l = 0.5, g = 9.81 }",
        "",
    ]
    xs: list[str] = []
    ys: list[str] = []
    depth = []  # the depth of each mass below the pivot, for the potential
    for c in names:
        xs.append(f"l*sin({c})")
        ys.append(f"l*cos({c})")
        x, y = " + ".join(xs), " + ".join(ys)
        depth.append(f"({y})")
        text += ["[[particles]]", 'mass = "m"', f'position = ["{x}", "-({y})"]', ""]
    text.insert(4, f'potential = "-m*g*({" + ".join(depth)})"')
    text += ["[initial]", "q = { " + ", ".join(f"{c} = 0.1" for c in names) + " }", ""]
    text += ["[simulate]", "t_end = 2.0", ""]
    return "\n".join(text)


def worker_setup_seconds(spec) -> float:
    """In a worker: seconds from the spec to a model ready to run (what a worker pays once)."""
    import sympy  # noqa: F401  (imports out of the timing)

    from pfaff.sweep.worker import _Compiled

    start = time.perf_counter()
    entry = _Compiled(spec)
    params, q0, qd0 = spec.run_inputs(0)
    entry.model(params).accelerations(0.0, q0, qd0)
    return time.perf_counter() - start


def ship_table(links: int, n: int, repeat: int) -> None:
    """Sweeps on 2 fresh workers: the compiled model shipped pickled against derived in each,
    with pfaff's on-disk code cache on (a second sweep of the file on this machine) and off (a
    first one, or workers on other machines)."""
    from dataclasses import replace

    import sympy
    from distributed import Client, LocalCluster

    from pfaff.sweep.grid import make_grid
    from pfaff.sweep.worker import SweepSpec

    folder = Path(tempfile.mkdtemp(prefix="pfaff-bench-ship-"))
    path = folder / "chain.toml"
    path.write_text(chain_file(links))
    mf = pfaff.load_model(path)
    coords = [f"th{i}" for i in range(1, links + 1)]
    vary = {"l": np.linspace(0.3, 0.6, n), "q0.th1": np.linspace(0.1, 0.8, n)}
    real = source.shipped_model
    blob = real(mf)  # fills the on-disk cache
    assert blob is not None
    base = SweepSpec(
        text=path.read_text(),
        filename=path.name,
        parameters=dict(mf.parameters),
        q0=tuple(float(x) for x in mf.q0),
        qd0=tuple(float(x) for x in mf.qd0),
        coordinates=tuple(coords),
        grid=make_grid(vary, list(mf.parameters), coords),
        t_eval=np.linspace(0.0, 2.0, 201),
    )
    specs = {"shipped": replace(base, model=blob), "derived in workers": base}

    def cluster() -> LocalCluster:
        return LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
            silence_logs=logging.ERROR,
        )  # fmt: skip

    saved = os.environ.get("PFAFF_CACHE")
    got: dict[tuple[str, str], dict[str, list[float]]] = {}
    driver_s: dict[str, list[float]] = {}
    ref = None
    try:
        for cache in ("on", "off"):
            os.environ["PFAFF_CACHE"] = "1" if cache == "on" else "0"  # the workers inherit it
            for i in range(repeat):
                sympy.core.cache.clear_cache()
                start = time.perf_counter()
                real(pfaff.load_model(path))
                driver_s.setdefault(cache, []).append(time.perf_counter() - start)
                order = list(specs) if i % 2 == 0 else list(specs)[::-1]
                for mode in order:
                    res = got.setdefault((cache, mode), {})
                    source.shipped_model = real if mode == "shipped" else (lambda _mf: None)
                    try:
                        with cluster() as c, Client(c) as client:
                            client.wait_for_workers(2)
                            client.run(lambda: __import__("pfaff.sweep.worker"))
                            setup = client.run(worker_setup_seconds, specs[mode])
                        res.setdefault("setup", []).extend(setup.values())
                        with cluster() as c:
                            for label in ("cold", "warm"):
                                start = time.perf_counter()
                                ds = pfaff.sweep(
                                    path, vary, scheduler=c.scheduler_address, progress=False
                                )
                                res.setdefault(label, []).append(time.perf_counter() - start)
                                assert int(ds.attrs["failed"]) == 0
                                ref = ds.q.values if ref is None else ref
                                np.testing.assert_allclose(ds.q.values, ref, rtol=0, atol=1e-12)
                    finally:
                        source.shipped_model = real
    finally:
        if saved is None:
            os.environ.pop("PFAFF_CACHE", None)
        else:
            os.environ["PFAFF_CACHE"] = saved
    load = os.getloadavg()
    print(
        f"shipped compiled model vs derived in workers: {links}-link chain (n = {links}), "
        f"{n * n} runs of 2 s, 2 fresh workers; medians of {repeat}; load average "
        f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"
    )
    start = time.perf_counter()
    pickle.loads(blob)
    print(
        f"the pickled model: {len(blob) / 1024:.0f} KiB, unpickled here in "
        f"{time.perf_counter() - start:.3f} s; wall s: cold = first sweep on a fresh cluster "
        "(driver's shipped_model included), warm = a second one on it; setup = per worker, "
        "from the spec to one accelerations call (unpickle, or derive + compile)"
    )
    head = (
        f"{'disk cache':<10} {'mode':<20} {'driver s':>9} {'cold s':>8} {'warm s':>8} "
        f"{'setup/worker s':>15}"
    )
    print(head)
    print("-" * len(head))
    for (cache, mode), res in got.items():
        med = {k: statistics.median(v) for k, v in res.items()}
        drv = statistics.median(driver_s[cache]) if mode == "shipped" else 0.0
        print(
            f"{cache:<10} {mode:<20} {drv:>9.3f} {med['cold']:>8.2f} {med['warm']:>8.2f} "
            f"{med['setup']:>15.3f}"
        )
    for cache in driver_s:
        ship, own = (statistics.median(got[cache, m]["setup"]) for m in specs)
        print(f"cache {cache}: per-worker setup, derived / shipped = {own / ship:.1f}x")


if __name__ == "__main__":
    sys.exit(main())
