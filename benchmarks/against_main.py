"""Benchmark: this checkout against another (``main``), row by row, in fresh processes, interleaved.

"Nothing that holds today gets slower by more than 15 %" (issue 25). Every row runs a small
script in a fresh subprocess whose ``PYTHONPATH`` is one checkout's ``src``; the two checkouts
alternate (``--pairs`` times, default 5, the first of a pair alternating too), with one shared
on-disk cache folder, so both run warm (generated code and machine code made by a first,
untimed round). Inside the subprocess the model is built and warmed up before the clock starts;
the row's figure is the median over ``--repeat`` loops (CPU µs per call, or CPU seconds per
run: ``time.process_time``, so that a busy machine's descheduling is not counted).
The table gives the medians over the pairs and the ratio new / base (< 1: faster now). All
processes use one BLAS thread.

Rows:

``rhs cart k``
    One right-hand side of :func:`pfaff.models.n_link_pendulum_on_cart` (k links), as
    ``simulate`` calls it (``on_lists`` where the model has it), µs.
``acc <model>``
    ``model.accelerations(t, q, q̇)`` at a consistent state, µs.
``run cart 8, F=0`` / ``F=0.7``
    ``pfaff.simulate`` of the 8-link chain for 10 s from a bent state, CPU s.
``run A01 200 s``
    :func:`pfaff.models.cartesian_pendulum` released from the horizontal, 200 s, rtol 1e-9,
    100 ``t_eval`` points, CPU s.
``run ring 64``
    The pushed ring (families) with N = 64 for 1 s, CPU s.

Run (from the project root)::

    python benchmarks/against_main.py --base /work/main/src
    python benchmarks/against_main.py --base ../main/src --rows "rhs cart 8" "acc bicycle" --pairs 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

PRELUDE = """
import time, statistics, warnings, numpy as np, pfaff
warnings.simplefilter("ignore")
from pfaff.models import n_link_pendulum_on_cart
def cart(k, F=0.7):
    eom = n_link_pendulum_on_cart(k).equations()
    values = {str(p): 1.0 + 0.05 * i for i, p in enumerate(eom.parameters)}
    values.update({"g": 9.81, "F": F})
    return eom.compile(values)
def per_call(fn, repeat, calls):
    fn()
    out = []
    for _ in range(repeat):
        t = time.process_time()
        for _ in range(calls):
            fn()
        out.append((time.process_time() - t) / calls * 1e6)
    return statistics.median(out)
def per_run(fn, repeat):
    fn()
    out = []
    for _ in range(repeat):
        t = time.process_time(); fn(); out.append(time.process_time() - t)
    return statistics.median(out)
"""

RHS = """
model = cart({k})
f = model.ode_function()
y = np.linspace(-0.4, 0.5, 2 * model.n); yl = y.tolist()
g = getattr(f, "on_lists", None)
print(per_call((lambda: g(0.0, yl)) if g else (lambda: f(0.0, y)), {repeat}, {calls}))
"""

ACC = """
name = {name!r}
if name == "cart 8":
    model = cart(8)
    q, qd = np.linspace(-0.4, 0.5, model.n), np.linspace(0.3, -0.2, model.n)
elif name == "pendulum":
    model = pfaff.models.cartesian_pendulum().equations().compile({{"m": 1, "g": 9.81, "L": 1}})
    q, qd = np.array([0.6, -0.8]), np.array([0.8, 0.6])
elif name == "bicycle":
    model = pfaff.models.whipple_bicycle().equations().compile(pfaff.models.MEIJAARD)
    q, qd = model.project(0.0, np.zeros(model.n), np.full(model.n, 0.5))[:2]
else:
    model = pfaff.models.andrews_squeezer().equations().compile(pfaff.models.ANDREWS)
    q, qd = model.project(0.0, np.zeros(model.n), np.zeros(model.n))[:2]
print(per_call(lambda: model.accelerations(0.0, q, qd), {repeat}, {calls}))
"""

RUN_CART = """
model = cart(8, F={F})
q0 = np.concatenate([[0.0], np.linspace(0.2, 0.6, 8)]); qd0 = np.zeros(9)
print(per_run(lambda: pfaff.simulate(model, q0, qd0, (0, 10.0)), {repeat}))
"""

RUN_A01 = """
model = pfaff.models.cartesian_pendulum().equations().compile({{"m": 1, "g": 9.81, "L": 1}})
te = np.linspace(0, 200, 100)
print(per_run(lambda: pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0, 200.0), t_eval=te), {repeat}))
"""

RUN_RING = """
N = 64
model = pfaff.models.rolling_ring(N, force=True, family=True).equations().compile({{"M": 1, "r": 0.5, "F": 2}})
q, qd = pfaff.models.ring_state(N, radius=0.5, theta=0.3)
print(per_run(lambda: pfaff.simulate(model, q, qd, (0, 1.0)), {repeat}))
"""

ROWS = {
    "rhs cart 8": (RHS, {"k": 8, "calls": 2000}, "µs"),
    "rhs cart 16": (RHS, {"k": 16, "calls": 1000}, "µs"),
    "rhs cart 32": (RHS, {"k": 32, "calls": 100}, "µs"),
    "acc pendulum": (ACC, {"name": "pendulum", "calls": 2000}, "µs"),
    "acc cart 8": (ACC, {"name": "cart 8", "calls": 1000}, "µs"),
    "acc bicycle": (ACC, {"name": "bicycle", "calls": 500}, "µs"),
    "acc andrews": (ACC, {"name": "andrews", "calls": 500}, "µs"),
    "run cart 8, F=0": (RUN_CART, {"F": 0.0}, "s"),
    "run cart 8, F=0.7": (RUN_CART, {"F": 0.7}, "s"),
    "run A01 200 s": (RUN_A01, {}, "s"),
    "run ring 64": (RUN_RING, {}, "s"),
}


def measure(src: str, script: str, cache: str) -> float:
    env = dict(os.environ, PYTHONPATH=src, XDG_CACHE_HOME=cache, OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")  # fmt: skip
    out = subprocess.run(
        [sys.executable, "-c", PRELUDE + script], env=env, capture_output=True, text=True
    )
    if out.returncode != 0:
        raise SystemExit(f"failed under {src}:\n{out.stderr[-2000:]}")
    return float(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="the other checkout's src folder")
    ap.add_argument("--new", default=str(Path(__file__).resolve().parent.parent / "src"))
    ap.add_argument("--rows", nargs="+", default=list(ROWS))
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    cache = tempfile.mkdtemp(prefix="pfaff-bench-cache-")
    print(f"# base {args.base}  new {args.new}; load {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores; {args.pairs} pairs, medians")  # fmt: skip
    print("| row | unit | base | new | new / base |")
    print("|---|---|---|---|---|")
    for name in args.rows:
        template, fields, unit = ROWS[name]
        script = template.format(repeat=args.repeat, **fields)
        for src in (args.base, args.new):  # untimed: fills the cache (code, machine code)
            measure(src, script, cache)
        got: dict[str, list[float]] = {"base": [], "new": []}
        for p in range(args.pairs):
            order = (("base", args.base), ("new", args.new))
            for key, src in order if p % 2 == 0 else order[::-1]:
                got[key].append(measure(src, script, cache))
        base, new = statistics.median(got["base"]), statistics.median(got["new"])
        fmt = ".1f" if unit == "µs" else ".3f"
        print(f"| {name} | {unit} | {base:{fmt}} | {new:{fmt}} | {new / base:.2f} |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
