"""Benchmark: a checked ``model.accelerations(t, q, q̇)`` against one right-hand side of the same model.

Issue 25's target: ``accelerations()`` at most 2× the right-hand side ``simulate`` calls
(``model.ode_function().on_lists`` on lists of floats where the model has a fused kernel, else
the array call). Both are timed in one process, alternating within each of ``--rounds`` rounds
(median CPU µs per call, ``time.process_time``: a busy machine's descheduling is not counted), at a state on the constraints (``model.project``); one BLAS thread.

A third column times the full checked path (:meth:`pfaff.NumericModel._checked_accelerations`:
the inertia test, the redundancy test and the solve on the assembled augmented matrix), which
``accelerations()`` took on every call before its fast path read the generated solve's pivots
(:func:`pfaff.numeric.checkedsolve.fused_accelerations`): the baseline, in the same run.

Models: the 8-link pendulum on a cart (no constraints), the Cartesian pendulum (one), Andrews'
squeezer (7 + 6), the Whipple bicycle (8 + 5) and a spatial 6R arm of point masses (6 + 0).

Run (from the project root)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/accelerations.py
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import warnings

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

import pfaff


def models() -> list[tuple[str, object]]:
    cart = pfaff.models.n_link_pendulum_on_cart(8).equations()
    values = {str(p): 1.0 + 0.05 * i for i, p in enumerate(cart.parameters)}
    return [
        ("cart 8", cart.compile(values)),
        ("pendulum", pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})),
        ("andrews", pfaff.models.andrews_squeezer().equations().compile(pfaff.models.ANDREWS)),
        ("bicycle", pfaff.models.whipple_bicycle().equations().compile(pfaff.models.MEIJAARD)),
        ("6R arm", pfaff.models.robot_arm(6).equations().compile(pfaff.models.robot_arm_values(6))),
    ]  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--calls", type=int, default=500)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"# load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; medians of {args.rounds}")
    print("| model | n+m | evaluator | accelerations µs | rhs µs | ratio | full path µs | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for name, model in models():
        n = model.n
        rng = np.random.default_rng(0)
        q, qd, _ = model.project(0.0, rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n))
        f = model.ode_function()
        y = np.concatenate([q, qd])
        yl = y.tolist()
        lists = getattr(f, "on_lists", None)
        fns = {
            "acc": lambda m=model, a=q, b=qd: m.accelerations(0.0, a, b),
            "rhs": (lambda g=lists, a=yl: g(0.0, a)) if lists else (lambda g=f, a=y: g(0.0, a)),
            "full": lambda m=model, a=q, b=qd: m._checked_accelerations(0.0, a, b),
        }
        fast, full = fns["acc"](), fns["full"]()
        assert np.allclose(np.concatenate(fast), np.concatenate(full), rtol=1e-9, atol=1e-12)
        times: dict[str, list[float]] = {key: [] for key in fns}
        for r in range(args.rounds):
            for key in ("acc", "rhs", "full") if r % 2 == 0 else ("full", "rhs", "acc"):
                fns[key]()
                start = time.process_time()
                for _ in range(args.calls):
                    fns[key]()
                times[key].append((time.process_time() - start) / args.calls * 1e6)
        acc, rhs, old = (statistics.median(times[key]) for key in ("acc", "rhs", "full"))
        print(
            f"| {name} | {n}+{model.m} | {model.evaluator} | {acc:.1f} | {rhs:.1f} | "
            f"{acc / rhs:.2f} | {old:.1f} | {old / rhs:.2f} |",
            flush=True,
        )


if __name__ == "__main__":
    sys.exit(main())
