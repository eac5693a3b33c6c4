"""Benchmark: IDA against the projection method on the pushed rolling ring (family model).

For each N the ring ``pfaff.models.rolling_ring(N, force=True, family=True)`` (M = 1, r = 0.5,
F = 2, θ(0) = 0.3 at rest) is compiled once and simulated over one second by
``method="projection"`` and ``method="ida"`` (the family's sparse Newton matrix,
:mod:`pfaff.numeric.ggl`), interleaved, ``--repeat`` times each; the table gives the median CPU
time of each (``time.process_time``: the machine is shared), their ratio, the model's first IDA
run ("ida 1st": it also finds the Newton matrix's pattern and band plan, which the model then
keeps for its later runs, :class:`pfaff.numeric.gglshape.NewtonShape`), IDA's steps and
factorizations, and the error of θ_1(1) against the closed form θ(1) = θ(0) + F/(4Mr) for both.
An IDA run is capped at ``--cap`` seconds (``max_seconds``; "cap" in the table).

``--closed``: the closed ring (``closed=True``: N + 1 rows, the last spacing dependent on the
others), whose DAE leaves that row out (``model.dae_model``) and takes the same sparse path.

Then the sizes IDA still refuses, with the estimate it gives (:mod:`pfaff.integrate.feasible`).
The issue's target is IDA within 10x the projection method's time at N = 2^16.

Measured 2026-11-28 (the next session) on an idle machine (load average 0.0-1.0), CPU seconds,
medians of five, with the narrow band path (:mod:`pfaff.numeric.bandlu`: fixed widths, the open
rows in registers, the compact factors written by the factorization), ``KEEP_RATIO`` = 16 and
the Newton matrix's local differences taking sin and cos in the compiled pass::

          N    proj s     ida s  ida/proj   ida 1st ida steps  factor.  proj err   ida err
       1024     0.011     0.028       2.5     0.032        23        3   6.7e-16   3.7e-09
       4096     0.019     0.067       3.5     0.088        23        3   1.1e-15   3.7e-09
      16384     0.055     0.230       4.2     0.295        23        3   2.9e-15   3.7e-09
      65536     0.104     0.961       9.2     1.216        23        3   1.1e-15   3.7e-09

and at 2^16 in three more runs the same hour, alternated with the code before (954f581): 7.8,
6.8 and 7.6x (1.07, 0.88 and 0.98 s) against its 10.9, 10.9 and 9.8x (1.34, 1.16 and 1.42 s);
the projection method's own time moved between 0.104 and 0.145 s across these runs. The
closed ring 5.9x (1.23 s). A run at 2^16 is now about a third IDA's own vector work (17 ms a
step at 262 146 unknowns even for a trivial residual: memory-bound), 30 % the 46 preconditioner
solves (about 6 ms each: 4.3 ms the band's, from memory, the rest the border's and the call's),
15 % the residuals and 12 % the 3 factorizations (about 40 ms each: the terms' values 8, their
assembly 13, the band 11, the border's two columns 9).

Earlier, at the end of the previous session, on an idle machine (load average 0.3-0.6), CPU
seconds, medians of three, two runs (``KEEP_RATIO`` = 8; the pattern and band plan kept by the
model, λ and μ scaled under one scalar tolerance, single right sides by a vector loop, the
work integral at the power's coordinates)::

          N    proj s     ida s  ida/proj   ida 1st ida steps  factor.  proj err   ida err
       1024     0.018     0.054       3.1     0.063        23        4   6.7e-16   2.6e-09
      16384     0.064     0.373       5.8     0.453        23        4   2.9e-15   2.6e-09
      65536     0.121     1.226      10.1     1.539        23        4   1.1e-15   2.6e-09

and 3.3, 5.8 and 10.7x in the second run (1.224 s against 0.114 s); the closed ring 7.2x
(1.479 s). Other runs within the hour: 8.1-9.9x. The code before (8239fcc), alternated the same
hour: 1.68-1.91 s, 13.0-13.6x its own projection method (0.13-0.14 s), which today's changes to
the projection method made 15-25 % faster. A run at 2^16 is now about a quarter each IDA's own
vector work, the preconditioner solves (49, about 6.5 ms each: a band substitution whose rows
are half interchanged, the λ rows' diagonal being the regularization alone, U's band 8 wide),
the 4 factorizations (57 ms each: the terms' values 14 ms, their assembly 12, the band LU 14,
the compact copy 6, the border's two columns 8), and the residuals with the rest.

Earlier that day, before those changes (``KEEP_RATIO`` = 6), idle::

          N    proj s     ida s  ida/proj ida steps  factor.  proj err   ida err
       1024     0.023     0.083       3.7        23        5   1.1e-15   2.1e-09
      16384     0.098     0.686       7.0        23        5   2.2e-16   2.1e-09
      65536     0.192     2.555      13.3        23        5   2.2e-16   2.1e-09

and 2.3, 6.9 and 12.6x in the second run: idle, the target (10x at 2^16) is missed. ``KEEP_RATIO``
3 against 6, alternated at 2^16: 3.02/2.75, 2.84/2.41, 2.62/2.42 s. The closed ring
(``--closed``, ratio 3): 2.75 s, 9.9x in one run. A run at 2^16 is 23 steps of IDA's own vector
work (GMRES, about 15 % of the run), 5 factorizations (a band LU with half its rows
interchanged, the λ rows' diagonal being the regularization alone: U's band is then 8 wide, not
4), about 53 preconditioner solves (7 ms each: the band substitutions are a chain of dependent
updates, latency-bound, not memory-bound), the residuals, and the setup (pattern, reverse
Cuthill–McKee, SUNDIALS: about 0.4 s).

Earlier the same day, on the machine shared with other runs (load average 6.7), ratio 3::

          N    proj s     ida s  ida/proj ida steps  factor.  proj err   ida err
       1024     0.019     0.054       2.9        19        7   1.1e-15   2.5e-09
       4096     0.021     0.129       6.3        19        7   1.6e-15   2.5e-09
      16384     0.060     0.464       7.7        19        7   2.2e-16   2.6e-09
      65536     0.206     1.759       8.5        19        7   1.1e-15   2.6e-09

Another run the same minutes (load 7.8): 9.0 at 2^16 (2.372 s), 3.7 at 2^10. The code before
the kept factors and the compact band solves, run between those two (load 7.2): 10.9 at 2^16
(2.878 s, 14 factorizations), 4.9 at 2^10; by pairs of runs alternated, medians of three (load
8.4 to 9): 3.00 and 3.08 s before, 2.62 and 1.95 s after at 2^16 (10.8 and 9.6x before, 7.7
and 8.8x after); 0.092 s before, 0.050 s after at 2^10.

Earlier (2026-11-27, load 7 to 11, one repeat): 43 steps and 35 SuperLU factorizations of about
0.3 to 0.5 s each at 2^16, 15.2 s (41x); 0.241 s (7.9x) at 2^10. The Newton matrix is a band
with a dense border (numeric.bordered: 0.03 to 0.06 s a factorization at 2^16) and IDA's first
step comes from its first-order local error (h0 about 2e-5 instead of 5e-12: 19 steps). The
factors are kept while c_j stays within a factor 3 of theirs (numeric.ggl ``KEEP_RATIO``: 7
factorizations instead of 14, GMRES iterating a little more). At 2^16 a run is now about 7
factorizations (assembly included, 40-60 ms each), 53 preconditioner solves (7 to 9 ms: the
compact band factors, read once per solve), 53 residuals (3 to 5 ms), IDA's own vector work
(about 0.4 s) and its setup (pattern, band plan, SUNDIALS: 0.25-0.45 s); the band's work is
bound by memory traffic. The target (10x at 2^16) was met in those runs (7.7 to 9.0), on a
loaded machine, where the projection method's own time varies by 50 %.
Numba's band LU loads once per process (about 0.9 s; 2 s compiling the first time): the
warm-up takes it. Before the band path, IDA on a family was dense: 214 s at N = 1024, refused
from about 2000 members on. N = 2^22 and 2^24 are refused (about 22 and 88 GiB estimated from
SuperLU's fill, against half the memory available: 15 to 22 GiB).

Run from the project root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/ida_ring.py            # N = 2^10, 2^12, 2^14, 2^16
    python benchmarks/ida_ring.py --sizes 1024 4096 --repeat 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings

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
    ap.add_argument("--closed", action="store_true", help="the closed ring (a dependent row)")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()}, OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS')}")  # fmt: skip
    head = ("N", "proj s", "ida s", "ida/proj", "ida 1st", "ida steps", "factor.", "proj err",
            "ida err")  # fmt: skip
    print("{:>7} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8} {:>9} {:>9}".format(*head))
    # imports, caches, and numba's band LU (loaded once per process from WARM members on)
    warm = pfaff.models.rolling_ring(WARM, force=True, family=True).equations()
    warm = warm.compile({"M": M_, "r": R_, "F": F_})
    run(warm, WARM, "projection", args.cap), run(warm, WARM, "ida", args.cap)
    for n in args.sizes:
        ring = pfaff.models.rolling_ring(n, force=True, family=True, closed=args.closed)
        with warnings.catch_warnings():  # (the closed ring's RedundancyWarning)
            warnings.simplefilter("ignore", pfaff.RedundancyWarning)
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
            f"{n:>7} {tp:>9.3f} {ti:>9.3f} {ti / tp:>9.1f} {ida[0][0]:>9.3f} "
            f"{last[1].get('steps', 0):>9} "
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
