"""Benchmark: the rolling ring's build with the family rank check on a small instance, against the full check.

Issue 25: "87 % of the 2^24 build is the constraint rank check on a full-size model"; target:
the 2^24 build <= 5 s. For each N, one process, CPU seconds (``time.process_time``, medians of
``--rounds``, the two checks alternating within each round, on the same ``Derivation``):

``small``
    ``check_constraint_rank(eom)``: the templates on a small instance
    (:func:`pfaff.derive.family_rank.proves_full_rank`), what ``equations()`` runs now
``full``
    ``check_constraint_rank(eom, small_instance=False)``: the check as it was, a numeric model
    of full size (N <= ``--full-max``)
``equations``, ``compile``
    ``rolling_ring(N, force=True).equations()`` (with the small check) and ``.compile(values)``
    once; ``build`` is their sum, ``old build`` = build − small + full (N <= ``--full-max``)

``--closed``: the closed ring instead (``closed=True``: N + 1 rows, the N spacing rows one
dependent set), whose small check is :func:`pfaff.derive.family_rank.closure_rows` (one banded
solve) above the dense limit; the full check finds the null space of the sparse Aᵀ by inverse
iteration (keep ``--full-max`` small: 2^16 took about a second).

Run (from the project root)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/family_rank.py
    python benchmarks/family_rank.py --sizes 65536 1048576 --full-max 1048576
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import sys
import time
import warnings

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pfaff
from pfaff.derive.rank import check_constraint_rank

SIZES = [2**16, 2**20, 2**22, 2**24]


def cpu(fn) -> float:
    start = time.process_time()
    fn()
    return time.process_time() - start


def row(n: int, rounds: int, full_max: int, closed: bool = False) -> str:
    ring = pfaff.models.rolling_ring(n, force=True, family=True, closed=closed)
    made: list = []
    eqs = cpu(lambda: made.append(ring.equations()))
    eom = made[0]
    comp = cpu(lambda: eom.compile({"M": 1.0, "r": 0.5, "F": 2.0}))
    gc.collect()
    times: dict[str, list[float]] = {"small": [], "full": []}
    keys = ["small", "full"] if n <= full_max else ["small"]
    for r in range(rounds):
        for key in keys if r % 2 == 0 else keys[::-1]:
            small = key == "small"
            times[key].append(cpu(lambda s=small: check_constraint_rank(eom, small_instance=s)))
            gc.collect()
    small = statistics.median(times["small"])
    build = eqs + comp
    if times["full"]:
        full = statistics.median(times["full"])
        old = f"{full:8.3f} | {build - small + full:9.2f}"
    else:
        old = f"{'-':>8} | {'-':>9}"
    return f"| {n:>9} | {small:8.4f} | {old} | {eqs:9.3f} | {comp:7.3f} | {build:6.2f} |"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=SIZES)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--full-max", type=int, default=2**22)
    ap.add_argument("--closed", action="store_true", help="the closed ring (one redundant row)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    print(
        f"# load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; CPU s, medians of {args.rounds}"
    )
    print("| N | small | full | old build | equations | compile | build |")
    print("|---|---|---|---|---|---|---|")
    for n in args.sizes:
        print(row(n, args.rounds, args.full_max, args.closed), flush=True)
        gc.collect()
    return 0


if __name__ == "__main__":
    sys.exit(main())
