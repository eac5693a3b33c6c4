"""Benchmark: the cost of forward sensitivities against a plain run of the same model.

The damped double pendulum (``pfaff.models.damped_double_pendulum``) in its angles and in
Cartesian coordinates (two rods), 10 s from (0.8, −0.4) rad at rtol 1e-9: ``pfaff.simulate``
(the baseline) and ``pfaff.sensitivities`` with p = 1, 3 and 6 parameters (and p = 3 with the
initial values), interleaved run by run, medians of the CPU time of each. The sensitivities are
left out of the step-size control, so both take the same steps (printed). The issue's target is
a ratio ≤ 2(1 + p). With ``--bicycle`` also the Whipple bicycle at 4.6 m/s over 2 s with p = 2
(rear wheel radius, trail). The first sensitivity call of each parameter set generates its code
and is not timed. Run from the project root::

    python benchmarks/sensitivity.py [--repeats 7] [--bicycle]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import pfaff
from pfaff.models import damped_double_pendulum, double_pendulum_cartesian_state

VALUES = {"m1": 1.0, "m2": 1.5, "l1": 1.0, "l2": 0.8, "g": 9.81, "c": 0.3}
ANGLES, RATES = [0.8, -0.4], [0.0, 0.5]
SETS = {1: ["c"], 3: ["m1", "l2", "c"], 6: list(VALUES)}


def _cpu(fn):
    t0 = time.process_time()
    out = fn()
    return out, time.process_time() - t0


def compare(model, q0, qd0, t_end: float, sets: dict, repeats: int, initial: bool) -> list:
    """Rows (case, p, steps, median CPU s, ratio to the plain run), runs interleaved."""
    cases = {"plain": lambda: pfaff.simulate(model, q0, qd0, (0, t_end))}
    for p, names in sets.items():
        cases[f"p = {p}"] = lambda names=names: pfaff.sensitivities(
            model, q0, qd0, (0, t_end), parameters=names
        )
        if initial and p == 3:
            cases[f"p = {p} + initial"] = lambda names=names: pfaff.sensitivities(
                model, q0, qd0, (0, t_end), parameters=names, initial=True
            )
    for fn in cases.values():
        fn()  # code generated, caches warm
    times: dict[str, list[float]] = {k: [] for k in cases}
    steps = {}
    for _ in range(repeats):
        for key, fn in cases.items():
            run, cpu = _cpu(fn)
            times[key].append(cpu)
            steps[key] = run.stats["steps"]
    base = float(np.median(times["plain"]))
    rows = []
    for key in cases:
        med = float(np.median(times[key]))
        cols = 0 if key == "plain" else len(SETS[int(key.split()[2])])
        if "initial" in key:
            cols += 2 * model.n
        rows.append((key, cols, steps[key], med, med / base, 2 * (1 + cols)))
    return rows


def table(title: str, rows: list) -> None:
    print(f"\n{title}")
    print(f"{'case':<18}{'columns':>8}{'steps':>7}{'CPU s':>10}{'ratio':>8}{'target':>8}")
    for key, cols, steps, med, ratio, target in rows:
        tgt = "" if key == "plain" else f"{target:>8.0f}"
        print(f"{key:<18}{cols:>8}{steps:>7}{med:>10.4f}{ratio:>8.2f}{tgt}")


def bicycle_rows(repeats: int) -> list:
    from pfaff.models.bicycle import bicycle_state

    bike = pfaff.models.whipple_bicycle()
    values = dict(pfaff.models.MEIJAARD)
    model = bike.equations().compile(values)
    q0, qd0 = bicycle_state(values, speed=4.6, phi=0.05, delta=0.02)
    return compare(model, q0, qd0, 2.0, {2: ["rR", "c"]}, repeats, False)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--bicycle", action="store_true", help="also the Whipple bicycle (slow)")
    args = ap.parse_args()
    angles = damped_double_pendulum().equations().compile(VALUES)
    rows = compare(angles, ANGLES, RATES, 10.0, SETS, args.repeats, True)
    table("double pendulum with joint dampers, angles (n = 2), 10 s, rtol 1e-9", rows)
    cart = damped_double_pendulum(cartesian=True).equations().compile(VALUES)
    q0, qd0 = double_pendulum_cartesian_state(ANGLES, RATES, VALUES)
    rows = compare(cart, q0, qd0, 10.0, SETS, args.repeats, False)
    table("the same, Cartesian (n = 4, m = 2)", rows)
    if args.bicycle:
        SETS[2] = ["rR", "c"]
        table("Whipple bicycle, 4.6 m/s, 2 s", bicycle_rows(args.repeats))


if __name__ == "__main__":
    main()
