"""Benchmark: one right-hand side of pfaff against Pinocchio's ``aba`` and MuJoCo's ``mj_forward``.

Systems (the same masses, lengths and gravity in all three engines):

``cart k``
    :func:`pfaff.models.n_link_pendulum_on_cart` with k links (k + 1 coordinates, absolute
    angles); in Pinocchio and MuJoCo a prismatic joint along x and k revolute joints about z
    (relative angles), a point mass at the end of each link (MuJoCo needs an inertia: 1e-12).
``arm 6R``
    A spatial arm of six revolute joints (axes z, y, y, x, y, x), a point mass at the end of each
    link, as pfaff particles in relative joint angles.

Before timing, each row checks that the engines agree: pfaff's q̈ (converted to relative angles)
against ``aba`` to 1e-8 and against MuJoCo's ``qacc`` to 1e-5 (its 1e-12 inertias), at a random
state with a push on the cart.

Timed (µs per call, single BLAS thread, ``time.process_time``: CPU time, so that a busy machine's descheduling is not counted): pfaff's right-hand side as
``simulate`` calls it (``model.ode_function().on_lists`` on lists of floats where the model has a
fused kernel, else the array call), warm (compiled, machine code built or loaded from the cache);
``pin.aba(model, data, q, v, tau)``; ``mj_forward`` after writing ``qpos``, ``qvel`` and
``qfrc_applied``. The engines alternate in every round (``--rounds``, default 7, of ``--calls``
calls each) and the table gives the medians over the rounds and the ratios. Above the fused limit
(n + m > 32) the row ``pfaff python`` is the model with the generated Python kernel
(``evaluator="python"``): the path every such model took before issue 25, measured in the same
run as the baseline of "no cliff". Consecutive sizes (31 and 32 links) are timed once more in
the same rounds and the step between them printed under the table (the rows are timed one
after the other, and the machine's load changes between them). Compile times are CPU seconds
from ``model.timings`` (``codegen``, ``machine_code``; a second run loads both from the on-disk
cache); ``compiled_solve`` s is LLVM's JIT compile of the right-hand side's Cholesky solve
above the fused limit (once per process, about 0.2 s).

Targets (issue 25): pfaff ≤ 1.5× ``aba`` for chains of 2 to 16 links and the 6R arm; ≤ 3× ``aba``
and ≤ 2× ``mj_forward`` at 32 and 64 links; no step above 1.5× between consecutive sizes.

Needs the ``bench`` extra (``pip install -e .[bench]``: mujoco, pin). Run (from the project root)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/engines.py             # 2 4 8 16 31 32 48 64 links, arm
    OPENBLAS_NUM_THREADS=1 python benchmarks/engines.py --links 8 32 --no-arm --rounds 5
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Callable

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import sympy as sp

import pfaff

G, PUSH = 9.81, 0.7
ARM_AXES = ("z", "y", "y", "x", "y", "x")
ARM_OFFSETS = ((0, 0, 0.3), (0.4, 0, 0), (0.35, 0, 0), (0, 0.1, 0.2), (0.15, 0, 0), (0, 0, 0.1))
ARM_MASSES = (2.0, 1.5, 1.2, 0.8, 0.5, 0.3)


def chain_values(k: int) -> tuple[list[float], list[float]]:
    """Masses m0..mk and lengths l0..l(k-1) of the k-link chain on a cart."""
    return [1.0 + 0.05 * i for i in range(k + 1)], [0.5 + 0.01 * i for i in range(k)]


def _rot(axis: str, a: sp.Expr) -> sp.Matrix:
    c, s = sp.cos(a), sp.sin(a)
    if axis == "x":
        return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "y":
        return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def arm_system() -> pfaff.System:
    """The spatial 6R arm: joint k turns about its axis; the mass of link k sits at its offset."""
    q = pfaff.coordinates("a1:7")
    s = pfaff.System(list(q), name="6R arm")
    R, p = sp.eye(3), sp.zeros(3, 1)
    V = sp.S.Zero
    for k in range(6):
        R = R * _rot(ARM_AXES[k], q[k])
        p = p + R * sp.Matrix(ARM_OFFSETS[k])
        s.add_particle(ARM_MASSES[k], list(p), name=f"m{k + 1}")
        V += ARM_MASSES[k] * G * p[2]
    s.add_potential_energy(V, name="gravity")
    return s


# ---------------------------------------------------------------------- Pinocchio and MuJoCo
def pin_chain(k: int) -> tuple:
    import pinocchio as pin

    masses, lengths = chain_values(k)
    model = pin.Model()
    model.gravity.linear = np.array([0.0, -G, 0.0])
    parent = model.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "cart")
    model.appendBodyToJoint(parent, pin.Inertia.FromSphere(masses[0], 0.0), pin.SE3.Identity())
    for i in range(1, k + 1):
        where = pin.SE3(np.eye(3), np.array([0.0, lengths[i - 2], 0.0]) if i > 1 else np.zeros(3))
        parent = model.addJoint(parent, pin.JointModelRZ(), where, f"j{i}")
        mass = pin.Inertia(masses[i], np.array([0.0, lengths[i - 1], 0.0]), np.zeros((3, 3)))
        model.appendBodyToJoint(parent, mass, pin.SE3.Identity())
    return model, model.createData()


def pin_arm() -> tuple:
    import pinocchio as pin

    joints = {"x": pin.JointModelRX, "y": pin.JointModelRY, "z": pin.JointModelRZ}
    model = pin.Model()
    model.gravity.linear = np.array([0.0, 0.0, -G])
    parent, where = 0, np.zeros(3)
    for k in range(6):
        parent = model.addJoint(parent, joints[ARM_AXES[k]](), pin.SE3(np.eye(3), where), f"a{k}")
        where = np.array(ARM_OFFSETS[k], dtype=float)
        model.appendBodyToJoint(
            parent, pin.Inertia(ARM_MASSES[k], where, np.zeros((3, 3))), pin.SE3.Identity()
        )
    return model, model.createData()


def _mj_body(name: str, pos: tuple, joint: str, mass: float, at: tuple, inner: str) -> str:
    p = " ".join(f"{x:.17g}" for x in pos)
    a = " ".join(f"{x:.17g}" for x in at)
    return (
        f'<body name="{name}" pos="{p}">{joint}<inertial pos="{a}" mass="{mass:.17g}" '
        f'diaginertia="1e-12 1e-12 1e-12"/>{inner}</body>'
    )


def _mj_model(gravity: str, bodies: str) -> tuple:
    import mujoco

    xml = (
        '<mujoco><compiler angle="radian"/><option gravity="' + gravity + '" timestep="0.001">'
        '<flag contact="disable"/></option><worldbody>' + bodies + "</worldbody></mujoco>"
    )
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model)


def mj_chain(k: int) -> tuple:
    masses, lengths = chain_values(k)
    inner = ""
    for i in range(k, 0, -1):
        joint = f'<joint name="j{i}" type="hinge" axis="0 0 1"/>'
        pos = (0.0, lengths[i - 2], 0.0) if i > 1 else (0.0, 0.0, 0.0)
        inner = _mj_body(f"b{i}", pos, joint, masses[i], (0.0, lengths[i - 1], 0.0), inner)
    cart = '<joint name="cart" type="slide" axis="1 0 0"/>'
    return _mj_model(f"0 {-G} 0", _mj_body("cart", (0, 0, 0), cart, masses[0], (0, 0, 0), inner))


def mj_arm() -> tuple:
    inner = ""
    for k in range(5, -1, -1):
        axis = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}[ARM_AXES[k]]
        pos = ARM_OFFSETS[k - 1] if k else (0.0, 0.0, 0.0)
        joint = f'<joint name="a{k}" type="hinge" axis="{axis}"/>'
        inner = _mj_body(f"l{k}", pos, joint, ARM_MASSES[k], ARM_OFFSETS[k], inner)
    return _mj_model(f"0 0 {-G}", inner)


# ---------------------------------------------------------------------- one row
class Row:
    """The engines of one system: callables of no argument, checked to agree first."""

    def __init__(self, name: str, k: int | None, evaluators: tuple[str, ...]) -> None:
        self.name, self.k = name, k
        if k is None:
            system, values = arm_system(), {}
            self.pin, self.mj = pin_arm(), mj_arm()
        else:
            system = pfaff.models.n_link_pendulum_on_cart(k)
            masses, lengths = chain_values(k)
            values = {f"m{i}": v for i, v in enumerate(masses)}
            values |= {f"l{i}": v for i, v in enumerate(lengths)} | {"g": G, "F": PUSH}
            self.pin, self.mj = pin_chain(k), mj_chain(k)
        eom = system.equations()
        self.models = {}
        for ev in evaluators:
            start = time.process_time()
            model = eom.compile(values, **({} if ev == "rule" else {"evaluator": ev}))
            f = model.ode_function()
            nq = model.n
            rng = np.random.default_rng(1)
            self.rel = rng.uniform(-0.6, 0.6, nq), rng.uniform(-0.6, 0.6, nq)
            y = self._pfaff_state()
            f(0.0, y)  # warm: machine code made or loaded
            model.timings["first call"] = time.process_time() - start
            self.models[ev] = (model, f, y)
        self.check()

    def _pfaff_state(self) -> np.ndarray:
        q, v = self.rel
        if self.k is None:
            return np.concatenate([q, v])
        return np.concatenate([[q[0]], np.cumsum(q[1:]), [v[0]], np.cumsum(v[1:])])

    def _tau(self) -> np.ndarray:
        tau = np.zeros(len(self.rel[0]))
        if self.k is not None:
            tau[0] = PUSH
        return tau

    def check(self) -> None:
        import mujoco
        import pinocchio as pin

        q, v = self.rel
        want = pin.aba(*self.pin, q, v, self._tau()).copy()
        mm, md = self.mj
        md.qpos[:], md.qvel[:], md.qfrc_applied[:] = q, v, self._tau()
        mujoco.mj_forward(mm, md)
        scale = np.abs(want).max()
        if np.abs(md.qacc - want).max() > 1e-5 * scale:
            raise SystemExit(f"{self.name}: MuJoCo disagrees with Pinocchio")
        for ev, (model, f, y) in self.models.items():
            acc = f(0.0, y)[model.n :]
            if self.k is not None:  # absolute angles back to relative ones
                acc = np.concatenate([[acc[0], acc[1]], np.diff(acc[1:])])
            if np.abs(acc - want).max() > 1e-8 * scale:
                raise SystemExit(f"{self.name}: pfaff ({ev}) disagrees with Pinocchio")

    def callables(self) -> dict[str, Callable[[], object]]:
        import mujoco
        import pinocchio as pin

        out: dict[str, Callable[[], object]] = {}
        for ev, (_, f, y) in self.models.items():
            lists = getattr(f, "on_lists", None)
            yl = y.tolist()
            if lists is not None:
                out[f"pfaff {ev}"] = lambda g=lists, a=yl: g(0.0, a)
            else:
                out[f"pfaff {ev}"] = lambda g=f, a=y: g(0.0, a)
        q, v = self.rel
        tau = self._tau()
        pm, pd = self.pin
        out["pin aba"] = lambda: pin.aba(pm, pd, q, v, tau)
        mm, md = self.mj

        def mj() -> None:
            md.qpos[:] = q
            md.qvel[:] = v
            md.qfrc_applied[:] = tau
            mujoco.mj_forward(mm, md)

        out["mj_forward"] = mj
        return out


def timed(fns: dict[str, Callable[[], object]], rounds: int, calls: int) -> dict[str, float]:
    """Median µs per call over ``rounds``, the callables alternating within each round."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    names = list(fns)
    for r in range(rounds):
        for name in names if r % 2 == 0 else reversed(names):
            fn = fns[name]
            start = time.process_time()
            for _ in range(calls):
                fn()
            times[name].append((time.process_time() - start) / calls * 1e6)
    return {k: statistics.median(v) for k, v in times.items()}


def _machine(timings: dict) -> str:
    """The machine code's kind, and for a kernel its LLVM opt level and count of functions."""
    kind = str(timings.get("machine_kind", ""))
    if "machine_functions" in timings:
        kind += f", O{timings.get('machine_opt_level')} × {timings['machine_functions']}"
    if "compiled_solve" in timings:  # the unconstrained solve: compiled loops, not LAPACK
        kind += ", one compiled call"
    return kind


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, nargs="+", default=[2, 4, 8, 16, 31, 32, 48, 64])
    ap.add_argument("--no-arm", action="store_true")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--calls", type=int, default=0, help="per round (default: by size)")
    args = ap.parse_args(argv)
    systems: list[tuple[str, int | None]] = [(f"cart {k}", k) for k in args.links]
    if not args.no_arm:
        systems.append(("arm 6R", None))
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S')}  load {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores; BLAS threads {os.environ['OPENBLAS_NUM_THREADS']}")  # fmt: skip
    print(
        "| system | n+m | pfaff µs | aba µs | mj_forward µs | ×aba | ×mj | pfaff python µs "
        "(before) | before/now | evaluator | codegen s | machine s | compiled_solve s |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    rows: dict[int, Row] = {}
    for name, k in systems:
        big = k is not None and k + 1 > 32
        row = Row(name, k, ("rule", "python") if big else ("rule",))
        if k is not None and (k - 1 in args.links or k + 1 in args.links):
            rows[k] = row
        model = row.models["rule"][0]
        calls = args.calls or max(20, int(20000 / (model.n + model.m) ** 1.5))
        t = timed(row.callables(), args.rounds, calls)
        now, aba, mj = t["pfaff rule"], t["pin aba"], t["mj_forward"]
        before = t.get("pfaff python")
        timings = model.timings
        cells = [
            name, str(model.n + model.m), f"{now:.1f}", f"{aba:.1f}", f"{mj:.1f}",
            f"{now / aba:.2f}", f"{now / mj:.2f}",
            "" if before is None else f"{before:.1f}",
            "" if before is None else f"{before / now:.1f}",
            f"{model.evaluator} ({_machine(timings)})",
            f"{timings.get('codegen', 0.0):.2f}", f"{timings.get('machine_code', 0.0):.2f}",
            f"{timings['compiled_solve']:.2f}" if "compiled_solve" in timings else "",
        ]  # fmt: skip
        print("| " + " | ".join(cells) + " |", flush=True)
    for k in sorted(rows):
        if k + 1 in rows:
            print(step(rows[k], rows[k + 1], args.rounds), flush=True)


def step(small: Row, large: Row, rounds: int) -> str:
    """The step between consecutive sizes, their right-hand sides timed in the same rounds
    (the rows of the table are timed one after the other, and the load changes between them)."""
    a, b = small.callables()["pfaff rule"], large.callables()["pfaff rule"]
    t = timed({"small": a, "large": b}, rounds, max(20, int(20000 / (large.k + 1) ** 1.5)))
    return (
        f"step cart {small.k} -> cart {large.k} (timed together): {t['small']:.1f} -> "
        f"{t['large']:.1f} µs, ×{t['large'] / t['small']:.2f}"
    )


if __name__ == "__main__":
    sys.exit(main())
