"""Benchmark: the thread policy of family models (the ring), decided here once.

Large family kernels can run their chunks on a second thread (``pfaff.numeric.streams.THREADS``,
``PFAFF_KERNEL_THREADS=1`` turns it off); BLAS is limited to one thread inside ``simulate`` and
``accelerations`` (``pfaff.numeric.value.single_threaded``). This script times, for the pushed ring
(family form), one checked ``accelerations()`` at N = 2^20 and 2^22 and a short ``simulate`` at
N = 2^18, with one kernel thread against two. Each variant runs in its own subprocess (the
setting is read at import), the two alternate (ABAB...), and the table gives the medians of wall
and CPU time and the paired ratio two/one (below 1: the second thread helps). Optionally two
``python -c "while 1: pass"`` processes load the machine (``--load``), as a Dask sweep with two
workers would. Run from the project root::

    python benchmarks/threads.py                 # 5 pairs, idle machine
    python benchmarks/threads.py --pairs 7 --load
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

CHILD = r"""
import json, sys, time
import numpy as np
import pfaff
kind, n = sys.argv[1], int(sys.argv[2])
model = pfaff.models.rolling_ring(n, force=True, family=True).equations().compile(
    {"M": 1.0, "r": 0.5, "F": 2.0})
q, qd = pfaff.models.ring_state(n, radius=0.5, theta=0.3, theta_dot=1.0)
model.accelerations(0.0, q, qd)  # warm
w, c = time.perf_counter(), time.process_time()
if kind == "acc":
    for _ in range(5):
        qdd, lam = model.accelerations(0.0, q, qd)
    reps = 5
else:
    traj = pfaff.simulate(model, q, qd, (0.0, 0.02), t_eval=[0.0, 0.02], max_step=0.002)
    assert traj.status == "success", traj.message
    reps = 1
print(json.dumps({"wall": (time.perf_counter() - w) / reps, "cpu": (time.process_time() - c) / reps}))
"""

CASES = [("acc", 2**20), ("acc", 2**22), ("sim", 2**18)]


def run(kind: str, n: int, threads: int) -> dict:
    env = {**os.environ, "PFAFF_KERNEL_THREADS": str(threads)}
    out = subprocess.run(
        [sys.executable, "-c", CHILD, kind, str(n)], env=env, capture_output=True, text=True,
        check=True,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--load", action="store_true", help="two busy-loop processes meanwhile")
    args = ap.parse_args()
    load = []
    try:
        if args.load:
            load = [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(2)]
        print(f"pairs {args.pairs}, load {'on' if load else 'off'}, {os.cpu_count()} cores")
        print(
            f"{'case':>14} {'one wall':>9} {'two wall':>9} {'ratio':>6} {'one cpu':>8} {'two cpu':>8}"
        )
        for kind, n in CASES:
            one, two, ratios = [], [], []
            for k in range(args.pairs):
                order = (1, 2) if k % 2 == 0 else (2, 1)
                got = {t: run(kind, n, t) for t in order}
                one.append(got[1])
                two.append(got[2])
                ratios.append(got[2]["wall"] / got[1]["wall"])
            med = statistics.median
            print(
                f"{kind + ' 2^' + str(n.bit_length() - 1):>14} "
                f"{med(r['wall'] for r in one):9.3f} {med(r['wall'] for r in two):9.3f} "
                f"{med(ratios):6.2f} {med(r['cpu'] for r in one):8.3f} "
                f"{med(r['cpu'] for r in two):8.3f}  (paired ratios {min(ratios):.2f}-{max(ratios):.2f})"
            )
            time.sleep(0.1)
    finally:
        for p in load:
            p.kill()


if __name__ == "__main__":
    main()
