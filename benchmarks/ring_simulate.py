"""Benchmark: simulate the pushed rolling ring for 1 s of motion at N = 4096, 65536 and 2^20.

For every N a fresh subprocess (so that peak RSS is per N) builds ``pfaff.models.rolling_ring(N,
force=F)`` (the family form above N = 1024), starts it at rest with θ_1 = π and runs
``pfaff.simulate(model, q0, q̇0, (0, t_end))`` with the default method "projection" (DOP853, the
state projected onto the constraints after every step). The push is constant, so the motion is
uniformly accelerated and DOP853 alone would cross 1 s in four steps: ``max_step`` (default
t_end/50) makes it a real run of many steps. The reported states are ``--points`` times
(default 11): a trajectory keeps q, q̇, q̈, λ and two residual arrays per point, 48 N bytes each, so
401 points at N = 2^20 would need 20 GB for the result alone.

Two paths, run alternately in fresh subprocesses (``--paths``; medians over ``--repeat``):
``inplace`` (the default for long states: :class:`pfaff.integrate.inplace.InPlaceDOP853`,
stage sums on preallocated buffers, each one compiled pass over spans on the kernel threads) and ``scipy`` (SciPy's ``DOP853``, the path before it,
selected by raising ``inplace.INPLACE_MIN``). ``--output`` streams the reported states to a
netCDF file in ``--output-dir`` (``simulate(output=...)``, removed afterwards), so that only one
state is held in memory: what 2^24 particles need (``--sizes 16777216 --output --paths
inplace``).

Columns: N; path; simulated seconds; wall and CPU seconds of ``simulate`` (CPU counts every thread);
accepted steps; right-hand-side evaluations; max constraint residual (max |f|, |A q̇ + b| over the
reported states); max |x(t) - x0 - F t²/(4M)| (the closed form: ẍ = F/(2M)); friction error
max |λ_1 + F/2|; peak RSS of the process when ``simulate`` returns (build included, the
checks after it not).

Measured 2026-11-28 on the 2-core development machine (``--paths inplace``; the commit before
the compiled stage passes, 8239fcc, against the one after them, run alternately in one session
with ``OPENBLAS_NUM_THREADS=1``; medians; the 1-minute load 0.9–1.5, the runs' own threads
included; the other sessions' benchmarks came and went, hence the spread)::

         N  code     runs  wall s  CPU s   wall range   CPU range    residual  max x err
   1048576  before     4    21.5    25.2   19.1–23.4    22.3–27.3    3.8e-15   6.7e-16
   1048576  after      4    16.0    22.6   13.2–16.1    19.0–23.2    3.3e-15   8.9e-16
   1048576  before     4    19.3    22.7   18.8–21.3    22.0–24.9    (another series)
   1048576  after      4    14.0    20.3   13.5–15.0    19.9–21.8
   1048576  before     3    20.5    20.4   20.0–21.9    19.9–21.8    PFAFF_KERNEL_THREADS=1
   1048576  after      3    17.7    17.5   17.2–28.2    17.1–18.8    (one thread)
     65536  before     5    1.82    1.82   1.48–1.88                 3.4e-15   0
     65536  after      5    1.37    1.37   1.35–1.77                 3.7e-15   4.4e-16
      4096  before     5    0.38    0.38                             4.3e-15   4.4e-16
      4096  after      5    0.30    0.30                             4.3e-15   4.4e-16

The same 51 steps and 644 right-hand sides; λ_1's error 6.0e-14 at 2^20 both; x's error is one or
two units in the last place of x(1) ≈ 2.07 (4.4e-16) on both, the sums being ordered differently.
At 2^20 the wall time is 26 % shorter and the CPU time 10 % (15 % on one thread): the stage sums
(half of the CPU) run at one core's memory pace, and the second core halves their wall time.

Run from the project root::

    python benchmarks/ring_simulate.py                    # N = 4096, 65536, 2^20, 1 s
    python benchmarks/ring_simulate.py --quick            # N = 4096, 65536, 0.2 s
    python benchmarks/ring_simulate.py --sizes 1048576 --t-end 1 --json out.json
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

SIZES = [4096, 65536, 2**20]
M_, R_, F_ = 1.0, 0.5, 2.0


def one(n: int, t_end: float, max_step: float, points: int, path: str, out: str | None) -> dict:
    """Simulate one N (run in a subprocess) on one path, to a file ``out`` if given."""
    import numpy as np

    import pfaff
    from pfaff.integrate import inplace

    inplace.INPLACE_MIN = 0 if path == "inplace" else 2**62
    t0 = time.perf_counter()
    model = pfaff.models.rolling_ring(n, force=F_).equations().compile({"M": M_, "r": R_})
    build = time.perf_counter() - t0
    q0, qd0 = pfaff.models.ring_state(n, R_, theta=np.pi)
    t_eval = np.linspace(0.0, t_end, points)
    wall, cpu = time.perf_counter(), time.process_time()
    traj = pfaff.simulate(
        model, q0, qd0, (0.0, t_end), t_eval=t_eval, max_step=max_step, output=out
    )
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # before the checks below
    x_exact = q0[0] + F_ * traj.t**2 / (4 * M_)
    k = len(traj.t)  # (row by row: a streamed run's arrays are read from its file)
    residual = max(float(np.abs(traj.constraint_residual[i]).max()) for i in range(k))
    return {
        "N": n,
        "path": path + (" → nc" if out else ""),
        "load": os.getloadavg()[0],
        "t_end": float(traj.t[-1]),
        "status": traj.status,
        "build_s": build,
        "wall_s": wall,
        "cpu_s": cpu,
        "integrator_cpu_s": traj.stats.get("cpu_time"),
        "steps": int(traj.stats["steps"]),
        "nfev": int(traj.stats["nfev"]),
        "projections": int(traj.stats.get("projections", 0)),
        "points": len(traj.t),
        "residual": residual,
        "x_error": float(np.abs(traj.q[:, 0] - x_exact).max()),
        "friction_error": float(np.abs(traj.multipliers[:, 0] + F_ / 2).max()),
        "peak_rss_mb": peak,
        "file_mb": os.path.getsize(out) / 2**20 if out else None,
    }


def table(rows: list[dict]) -> str:
    """The printed table."""
    head = (
        f"{'N':>9} {'path':>12} {'t_end':>5} {'wall s':>7} {'CPU s':>7} {'steps':>5} {'nfev':>5} "
        f"{'residual':>9} {'max x err':>9} {'λ1 err':>8} {'rss MiB':>7} {'load':>5}  status"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r['N']:>9} {r['path']:>12} {r['t_end']:5.2f} {r['wall_s']:7.1f} {r['cpu_s']:7.1f} "
            f"{r['steps']:>5} {r['nfev']:>5} {r['residual']:9.1e} {r['x_error']:9.1e} "
            f"{r['friction_error']:8.1e} {r['peak_rss_mb']:7.0f} {r['load']:5.1f}  {r['status']}"
        )
    return "\n".join(lines)


def median_rows(rows: list[dict]) -> list[dict]:
    """Per (N, path): the run of median CPU time."""
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["N"], r["path"]), []).append(r)
    return [sorted(g, key=lambda r: r["cpu_s"])[len(g) // 2] for g in groups.values()]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=None)
    ap.add_argument("--t-end", type=float, default=None, help="simulated seconds (default 1)")
    ap.add_argument("--max-step", type=float, default=None, help="default t_end/50")
    ap.add_argument("--points", type=int, default=11, help="reported states (default 11)")
    ap.add_argument("--quick", action="store_true", help="N = 4096, 65536 for 0.2 s")
    ap.add_argument("--paths", nargs="+", default=["scipy", "inplace"],
                    choices=["scipy", "inplace"])  # fmt: skip
    ap.add_argument("--repeat", type=int, default=1, help="runs per (N, path); medians")
    ap.add_argument("--output", action="store_true", help="stream the states to a .nc file")
    ap.add_argument("--output-dir", default=None, help="where (default: a temporary folder)")
    ap.add_argument("--json", metavar="FILE")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--path", default="inplace", help=argparse.SUPPRESS)
    ap.add_argument("--out", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    sizes = args.sizes or ([4096, 65536] if args.quick else SIZES)
    t_end = args.t_end if args.t_end is not None else (0.2 if args.quick else 1.0)
    max_step = args.max_step if args.max_step is not None else t_end / 50
    if args.one:
        row = one(args.one, t_end, max_step, args.points, args.path, args.out)
        print(json.dumps(row))
        return 0
    folder = args.output_dir or tempfile.mkdtemp(prefix="ring_simulate.")
    rows = []
    for n in sizes:
        for _ in range(args.repeat):
            for path in args.paths:  # interleaved
                cmd = [sys.executable, os.path.abspath(__file__), "--one", str(n)]
                cmd += ["--t-end", str(t_end), "--max-step", str(max_step)]
                cmd += ["--points", str(args.points), "--path", path]
                out = os.path.join(folder, f"ring_{n}_{path}.nc") if args.output else None
                cmd += ["--out", out] if out else []
                done = subprocess.run(cmd, capture_output=True, text=True, check=False)
                if out and os.path.exists(out):
                    os.remove(out)
                if done.returncode:
                    print(f"N = {n} ({path}): failed\n{done.stderr[-2000:]}", file=sys.stderr)
                    continue
                rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
                print(table(rows[-1:]).splitlines()[-1], flush=True)
    print()
    print(
        f"Rolling ring pushed by F = {F_} (M = {M_}, r = {R_}) from rest, method 'projection', "
        f"max_step {max_step:g}, {args.points} reported states; {os.cpu_count()} CPUs; "
        f"medians of {args.repeat}"
    )
    print(table(median_rows(rows)))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
