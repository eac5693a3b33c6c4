"""Benchmark: IDA against the projection method on the pushed rolling ring (family model).

For each N the ring ``pfaff.models.rolling_ring(N, force=True, family=True)`` (M = 1, r = 0.5,
F = 2, θ(0) = 0.3 at rest) is compiled once and simulated over one second by
``method="projection"`` and ``method="ida"`` (the family's sparse Newton matrix,
:mod:`pfaff.numeric.ggl`), interleaved, ``--repeat`` times each; the table gives the median CPU
time of each (``time.process_time``: the machine is shared), their ratio, IDA's steps and
factorizations, and the error of θ_1(1) against the closed form θ(1) = θ(0) + F/(4Mr) for both.
An IDA run is capped at ``--cap`` seconds (``max_seconds``; "cap" in the table).

Then the sizes IDA still refuses, with the estimate it gives (:mod:`pfaff.integrate.feasible`).
The issue's target is IDA within 10x the projection method's time at N = 2^16.

Measured 2026-11-27 on the 2-core machine shared with other runs (load average 7 to 11), CPU
seconds, one repeat::

          N    proj s     ida s  ida/proj ida steps  factor.  proj err   ida err
       1024     0.031     0.241       7.9        43       35   1.1e-15   2.7e-09
       4096     0.101     0.849       8.4        43       35   6.7e-16   2.7e-09
      16384     0.113     3.215      28.4        43       35   1.1e-15   2.7e-09
      65536     0.367    15.178      41.4        43       35   1.1e-15   2.7e-09

IDA's 35 factorizations of about 0.3 s each (SuperLU, 2.2 times the matrix's 1.2 million
entries at 2^16) are most of its time: the target is not met (41x). Before, IDA on a family was
dense: 214 s at N = 1024, and refused from about 2000 members on. N = 2^22 and 2^24 are refused
(about 22 and 88 GiB estimated against 17.5 GiB available).

Run from the project root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/ida_ring.py            # N = 2^10, 2^12, 2^14, 2^16
    python benchmarks/ida_ring.py --sizes 1024 4096 --repeat 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

import pfaff
from pfaff.core.errors import OptionError
from pfaff.integrate.feasible import refuse_sparse_ida, sparse_ida_estimate

SIZES = [2**10, 2**12, 2**14, 2**16]
REFUSED = [2**22, 2**24]
WARM = 2048  # the warm-up ring: large enough for the compiled band LU (pfaff.numeric.bandlu)
M_, R_, F_, TH0 = 1.0, 0.5, 2.0, 0.3


def run(model, n: int, method: str, cap: float) -> tuple[float, dict, float, str]:
    """(CPU seconds, stats, θ_1(1) error, status) of one simulated second."""
    q, qd = pfaff.models.ring_state(n, radius=R_, theta=TH0)
    t0 = time.process_time()
    traj = pfaff.simulate(
        model, q, qd, (0.0, 1.0), method=method, t_eval=np.array([0.0, 1.0]),
        max_seconds=cap, throw=False,
    )  # fmt: skip
    cpu = time.process_time() - t0
    exact = TH0 + F_ / (4 * M_ * R_)
    err = abs(float(traj.q[-1, 1]) - exact) if traj.status == "success" else float("nan")
    return cpu, dict(traj.stats), err, traj.status


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=SIZES)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--cap", type=float, default=900.0, help="CPU seconds per IDA run at most")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()}, OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS')}")  # fmt: skip
    head = ("N", "proj s", "ida s", "ida/proj", "ida steps", "factor.", "proj err", "ida err")
    print("{:>7} {:>9} {:>9} {:>9} {:>9} {:>8} {:>9} {:>9}".format(*head))
    # imports, caches, and numba's band LU (loaded once per process from WARM members on)
    warm = pfaff.models.rolling_ring(WARM, force=True, family=True).equations()
    warm = warm.compile({"M": M_, "r": R_, "F": F_})
    run(warm, WARM, "projection", args.cap), run(warm, WARM, "ida", args.cap)
    for n in args.sizes:
        ring = pfaff.models.rolling_ring(n, force=True, family=True)
        model = ring.equations().compile({"M": M_, "r": R_, "F": F_})
        proj, ida = [], []
        for _ in range(args.repeat):  # interleaved
            proj.append(run(model, n, "projection", args.cap))
            ida.append(run(model, n, "ida", args.cap))
        tp = statistics.median(r[0] for r in proj)
        ti = statistics.median(r[0] for r in ida)
        last = ida[-1]
        status = "" if last[3] == "success" else f"  ({last[3]})"
        print(
            f"{n:>7} {tp:>9.3f} {ti:>9.3f} {ti / tp:>9.1f} {last[1].get('steps', 0):>9} "
            f"{last[1].get('njev', 0):>8} {proj[-1][2]:>9.1e} {last[2]:>9.1e}{status}",
            flush=True,
        )
    for n in REFUSED:
        size = 4 * n + 2
        seconds, nbytes = sparse_ida_estimate(size)
        try:
            refuse_sparse_ida(size, n + 1)
            verdict = "accepted"
        except OptionError as e:
            verdict = f"refused: {e}"
        print(f"N = {n}: estimate {seconds:.3g} s, {nbytes / 2**30:.3g} GiB; {verdict}")


if __name__ == "__main__":
    main()
