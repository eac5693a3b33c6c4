"""Benchmark: the compiled stepping loop (issue 25, item 2) against its baselines, in one run.

Two targets, each timed in rounds that alternate the contenders (CPU time,
``time.process_time``, medians over ``--rounds``; compile and first-call costs excluded: every
contender runs once before the clock starts; A01's compiled loop 20 times a round, per call, so
that it is timed over about as long as ``solve_ivp``: timed once a round, over 0.06-0.1 s, a
burst of the shared machine's load fell on it alone, and the ratio ran from 17 to 31 the same
hour):

``A01``
    :func:`pfaff.models.cartesian_pendulum` (m = 1, g = 9.81, L = 1) released from the
    horizontal, 2000 s in Cartesian form at rtol 1e-9 (atol 1e-11), 100 ``t_eval`` points,
    against ``scipy.integrate.solve_ivp(DOP853)`` on the one-angle equation θ̈ = −(g/L) sin θ
    written as a plain Python function, same tolerances and times. Target: pfaff at least 20×
    faster. Errors: the largest distance of the bob from the one-angle solution at rtol 1e-13.
``chain``
    :func:`pfaff.models.n_link_pendulum_on_cart` with 8 links (the masses, lengths and push of
    ``benchmarks/engines.py``), 10 s from a bent state at rest hanging below the cart (the
    angles are measured from the upward vertical: π + 0.2 … π + 0.6; the bent *inverted* chain of
    ``benchmarks/against_main.py`` is chaotic, its state at 10 s changes by O(1) between rtol
    1e-9 and 1e-12 in every engine, so no end error can be equal there), every step reported
    (pfaff's default). Baselines at equal end error: MuJoCo's RK4 (``mujoco.rollout``, the whole rollout
    in C) with the largest step 10/2^k whose end error is at most pfaff's, and ``solve_ivp
    (DOP853)`` on Pinocchio's ``aba`` at pfaff's tolerances. End error: max |q(10) − q_ref(10)|
    in relative joint angles, q_ref from ``solve_ivp(DOP853)`` on ``aba`` at rtol 1e-12. Target:
    pfaff faster than the MuJoCo rollout.

Both tables also give pfaff's Python path (``PFAFF_LOOP=0``: today's stepper before the loop),
measured in the same rounds, and the run's ``stats["stepping"]``.

Run (from the project root; needs the ``bench`` extra for the chain's baselines)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/loop.py
    OPENBLAS_NUM_THREADS=1 python benchmarks/loop.py --rounds 3 --skip-chain
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
from scipy.integrate import solve_ivp

import pfaff

sys.path.insert(0, str(Path(__file__).resolve().parent))
from engines import PUSH, chain_values, mj_chain, pin_chain

G, LINKS, SPAN = 9.81, 8, 10.0


def python_path(fn: Callable[[], object]) -> Callable[[], object]:
    """``fn`` run with ``PFAFF_LOOP=0`` (pfaff's Python stepper)."""

    def run() -> object:
        os.environ["PFAFF_LOOP"] = "0"
        try:
            return fn()
        finally:
            del os.environ["PFAFF_LOOP"]

    return run


def timed(
    fns: dict[str, Callable[[], object]], rounds: int, calls: dict[str, int] | None = None
) -> dict[str, float]:
    """Median CPU seconds per call over ``rounds``, the callables alternating in each round;
    ``calls[name]`` calls of a callable per round (default 1), so that a fast contender is timed
    over about as long as a slow one and a burst of the shared machine's load weighs on both
    alike."""
    calls = calls or {}
    for fn in fns.values():
        fn()  # warm: compiled, loaded, cached
    times: dict[str, list[float]] = {k: [] for k in fns}
    names = list(fns)
    for r in range(rounds):
        for name in names if r % 2 == 0 else reversed(names):
            k = calls.get(name, 1)
            start = time.process_time()
            for _ in range(k):
                fns[name]()
            times[name].append((time.process_time() - start) / k)
    return {k: statistics.median(v) for k, v in times.items()}


# ---------------------------------------------------------------------------------------- A01
def a01(rounds: int) -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": G, "L": 1})
    te = np.linspace(0.0, 2000.0, 100)

    def angle(t: float, y: list) -> list:
        return [y[1], -G * math.sin(y[0])]

    def ivp(rtol: float = 1e-9, atol: float = 1e-11) -> object:
        return solve_ivp(angle, (0, 2000), [math.pi / 2, 0.0], "DOP853", te, rtol=rtol, atol=atol)

    def run() -> pfaff.Trajectory:
        return pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0, 2000.0), t_eval=te)

    fns = {"pfaff (compiled loop)": run, "pfaff (Python path)": python_path(run), "ivp": ivp}
    t = timed(fns, rounds, {"pfaff (compiled loop)": 20})  # (about ivp's 2 s a round)
    exact = ivp(1e-13, 1e-13).y[0]
    bob = np.column_stack([np.sin(exact), -np.cos(exact)])
    err = {
        "pfaff (compiled loop)": np.abs(run().q - bob).max(),
        "pfaff (Python path)": np.abs(python_path(run)().q - bob).max(),
        "ivp": np.abs(np.column_stack([np.sin(ivp().y[0]), -np.cos(ivp().y[0])]) - bob).max(),
    }
    print("\n## A01: the Cartesian pendulum, 2000 s, rtol 1e-9, 100 t_eval points\n")
    print("| contender | CPU s | ivp / this | max bob error (m) | stepping |")
    print("|---|---|---|---|---|")
    stepping = {"pfaff (compiled loop)": run().stats["stepping"], "pfaff (Python path)": "python"}
    for name, s in t.items():
        print(f"| {name} | {s:.3f} | {t['ivp'] / s:.1f} | {err[name]:.1e} | "
              f"{stepping.get(name, '')} |")  # fmt: skip
    ratio = t["ivp"] / t["pfaff (compiled loop)"]
    print(f"\n{'PASS' if ratio >= 20 else 'FAIL'}: A01 compiled loop {ratio:.1f}× faster than "
          "solve_ivp on the one-angle equation (target ≥ 20×)")  # fmt: skip


# -------------------------------------------------------------------------------------- chain
def chain(rounds: int) -> None:
    import mujoco
    import pinocchio as pin
    from mujoco import rollout

    masses, lengths = chain_values(LINKS)
    values = {f"m{i}": v for i, v in enumerate(masses)}
    values |= {f"l{i}": v for i, v in enumerate(lengths)} | {"g": G, "F": PUSH}
    model = pfaff.models.n_link_pendulum_on_cart(LINKS).equations().compile(values)
    q0 = np.concatenate([[0.0], np.pi + np.linspace(0.2, 0.6, LINKS)])  # hanging, bent
    rel0 = np.concatenate([[q0[0], q0[1]], np.diff(q0[1:])])
    tau = np.zeros(LINKS + 1)
    tau[0] = PUSH
    pm, pd = pin_chain(LINKS)

    def aba(t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate(
            [y[LINKS + 1 :], pin.aba(pm, pd, y[: LINKS + 1], y[LINKS + 1 :], tau)]
        )

    def ivp(rtol: float = 1e-9, atol: float = 1e-11) -> np.ndarray:
        y0 = np.concatenate([rel0, np.zeros(LINKS + 1)])
        return solve_ivp(aba, (0, SPAN), y0, "DOP853", rtol=rtol, atol=atol).y[: LINKS + 1, -1]

    def run() -> pfaff.Trajectory:
        return pfaff.simulate(model, q0, np.zeros(LINKS + 1), (0, SPAN))

    def relative(q: np.ndarray) -> np.ndarray:
        return np.concatenate([[q[0], q[1]], np.diff(q[1:])])

    ref = ivp(1e-12, 1e-12)
    err_pfaff = np.abs(relative(run().q[-1]) - ref).max()
    mm, md = mj_chain(LINKS)
    mm.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    md.qpos[:], md.qvel[:] = rel0, 0.0
    state0 = np.empty(mujoco.mj_stateSize(mm, spec))
    mujoco.mj_getState(mm, md, state0, spec)
    control = tau[None, None, :]
    qfrc = mujoco.mjtState.mjSTATE_QFRC_APPLIED

    def mj(steps: int) -> np.ndarray:
        mm.opt.timestep = SPAN / steps
        states, _ = rollout.rollout(mm, md, state0, control, control_spec=qfrc, nstep=steps)
        return states[0, -1, 1 : 2 + LINKS]  # (time, then qpos)

    steps = 64
    while np.abs(mj(steps) - ref).max() > err_pfaff and steps < 2**22:
        steps *= 2
    err_mj = np.abs(mj(steps) - ref).max()
    fns = {
        "pfaff (compiled loop)": run,
        "pfaff (Python path)": python_path(run),
        f"MuJoCo RK4 rollout ({steps} steps)": lambda: mj(steps),
        "solve_ivp on Pinocchio aba": ivp,
    }
    t = timed(fns, rounds)
    errs = [err_pfaff, np.abs(relative(python_path(run)().q[-1]) - ref).max(), err_mj,
            np.abs(ivp() - ref).max()]  # fmt: skip
    mj_time = t[f"MuJoCo RK4 rollout ({steps} steps)"]
    print(
        f"\n## chain: {LINKS} links on a cart pushed by F = {PUSH}, {SPAN:g} s, equal end error\n"
    )
    print("| contender | CPU s | MuJoCo / this | end error (rad, m) | stepping |")
    print("|---|---|---|---|---|")
    stepping = run().stats["stepping"]
    for (name, s), e in zip(t.items(), errs, strict=True):
        note = stepping if name.endswith("loop)") else ("python" if "Python" in name else "")
        print(f"| {name} | {s:.4f} | {mj_time / s:.2f} | {e:.1e} | {note} |")
    ratio = mj_time / t["pfaff (compiled loop)"]
    print(f"\n{'PASS' if ratio > 1 else 'FAIL'}: the chain's compiled loop {ratio:.2f}× the speed "
          "of MuJoCo's RK4 rollout at equal end error (target > 1)")  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--skip-a01", action="store_true")
    ap.add_argument("--skip-chain", action="store_true")
    args = ap.parse_args(argv)
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S')}  load {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores; {args.rounds} rounds, medians of CPU time")  # fmt: skip
    if not args.skip_a01:
        a01(args.rounds)
    if not args.skip_chain:
        chain(args.rounds)


if __name__ == "__main__":
    sys.exit(main())
