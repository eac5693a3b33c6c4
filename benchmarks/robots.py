"""Benchmark: robot arms from a URDF file, pfaff against SymPy's KanesMethod, Pinocchio and MuJoCo.

The arm is :func:`pfaff.models.robot_arm_urdf` (n revolute joints about z, y, x, z, …, rods
between them, gravity along −z), for n = 3, 6, 12 in one run. Two measurements:

(i) **model → first q̈**, each in a fresh Python process (imports untimed, SymPy's cache cleared,
pfaff's code cache a new empty folder), wall-clock seconds:

``pfaff``
    ``load_urdf`` + ``equations()`` + ``compile(urdf_values)`` + one ``accelerations`` call.
``kane``
    the same tree (parsed by pfaff's URDF parser, untimed) as ``sympy.physics.mechanics``
    frames (``orient_axis``) and points, bodies with the file's numbers built in (not symbols:
    smaller expressions than pfaff's parametric model, the baseline's advantage), gravity loads,
    ``KanesMethod`` + ``kanes_equations`` + ``lambdify(cse=True)`` of ``mass_matrix`` and
    ``forcing`` + one ``numpy.linalg.solve``. A run over ``--timeout`` seconds is killed.

Interleaved (pfaff, kane, pfaff, kane, …), ``--repeats`` times, medians; the ratio kane / pfaff
(above 1: pfaff is faster).

(ii) **one right-hand side** q̈(q, q̇) at a random state, in µs (``timeit``, median of 7
interleaved rounds): pfaff's ``model.accelerations`` (checked, the user's call) and its
integrator right-hand side ``model.ode_function()`` with the default evaluator and with machine
code (``compile(..., evaluator="machine")``), Pinocchio's ``aba``
(``buildModelFromXML`` of the same text), MuJoCo's ``mj_forward`` (``MjModel.from_xml_string`` of
the same text: qpos, qvel set, q̈ read from ``qacc``), each with the largest |q̈ − Pinocchio| at
that state.

Run (from the project root; needs the ``bench`` extra: ``pip install -e .[bench]``)::

    python benchmarks/robots.py                 # n = 3, 6, 12
    python benchmarks/robots.py --n 3 6 --repeats 3
    python benchmarks/robots.py --rhs-only      # (ii) alone
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import timeit

import numpy as np


def _urdf(n: int) -> str:
    from pfaff.models import robot_arm_urdf

    return robot_arm_urdf(n)


def _state(n: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1000 + n)
    return rng.uniform(-np.pi, np.pi, n), rng.uniform(-2.0, 2.0, n)


# ---------------------------------------------------------------------------------------------
# (i) model → first q̈, one tool per process
# ---------------------------------------------------------------------------------------------


def _vector(values: tuple, frame):
    """Σ values_i e_i in ``frame``'s axes."""
    return float(values[0]) * frame.x + float(values[1]) * frame.y + float(values[2]) * frame.z


def kane_of(text: str):
    """KanesMethod of a URDF tree with its numbers built in: (kane, q, u)."""
    import sympy.physics.mechanics as me

    from pfaff.modelfile import urdf

    robot = urdf.parse_urdf(text)
    N = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(N, 0)
    frames = {robot.root: (N, origin)}
    q, u, kd, bodies, loads = [], [], [], [], []
    for jn in robot.order:
        j = robot.joints[jn]
        parent, at = frames[j.parent]
        fixed = me.ReferenceFrame(f"F_{jn}")
        fixed.orient_explicit(parent, urdf._rpy(j.rpy).T)  # the joint frame: parent → C
        point = at.locatenew(f"P_{jn}", _vector(j.xyz, parent))
        point.v2pt_theory(at, N, parent)
        qi, ui = me.dynamicsymbols(f"q_{jn} u_{jn}")
        q.append(qi)
        u.append(ui)
        kd.append(qi.diff() - ui)
        child = me.ReferenceFrame(f"L_{jn}")
        axis = _vector(j.axis, fixed)
        child.orient_axis(fixed, axis, qi)
        frames[j.child] = (child, point)
    for name, (frame, at) in frames.items():
        link = robot.links[name]
        if frame is N or link.inertial is None or link.inertial.mass == 0:
            continue
        ine = link.inertial
        centre = at.locatenew(f"G_{name}", _vector(ine.com, frame))
        centre.v2pt_theory(at, N, frame)
        i = ine.inertia
        dyadic = me.inertia(frame, i["ixx"], i["iyy"], i["izz"], i["ixy"], i["iyz"], i["ixz"])
        bodies.append(me.RigidBody(name, centre, frame, ine.mass, (dyadic, centre)))
        loads.append((centre, -ine.mass * 9.81 * N.z))
    kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(bodies, loads)
    return kane, q, u


def child(tool: str, n: int) -> dict:
    """One cold measurement in this process: seconds from model to the first q̈, and q̈."""
    import sympy as sp  # noqa: F401  (imports untimed)
    from sympy.core.cache import clear_cache

    import pfaff

    text = _urdf(n)
    q0, qd0 = _state(n)
    os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="pfaff-bench-")
    clear_cache()
    gc.collect()
    if tool == "pfaff":
        path = os.path.join(tempfile.mkdtemp(), "arm.urdf")
        with open(path, "w") as f:
            f.write(text)
        start = time.perf_counter()
        system = pfaff.load_urdf(path)
        model = system.equations().compile(system.urdf_values)
        qdd = model.accelerations(0.0, q0, qd0)[0]
        wall = time.perf_counter() - start
    else:
        import sympy

        start = time.perf_counter()
        kane, q, u = kane_of(text)
        M = sympy.lambdify([q, u], kane.mass_matrix, cse=True)
        F = sympy.lambdify([q, u], kane.forcing, cse=True)
        qdd = np.linalg.solve(M(q0, qd0), np.ravel(F(q0, qd0)))
        wall = time.perf_counter() - start
    return {"wall": wall, "qdd": [float(x) for x in qdd]}


def _spawn(tool: str, n: int, timeout: float) -> dict | None:
    cmd = [sys.executable, __file__, "--child", tool, "--n", str(n)]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=True)
    except subprocess.TimeoutExpired:
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])


# ---------------------------------------------------------------------------------------------
# (ii) one right-hand side
# ---------------------------------------------------------------------------------------------


def _pinocchio(text: str):
    import pinocchio as pin

    model = pin.buildModelFromXML(text)
    data = model.createData()

    def config(q: np.ndarray) -> np.ndarray:
        out = np.empty(model.nq)  # continuous joints: (cos q, sin q)
        out[0::2], out[1::2] = np.cos(q), np.sin(q)
        return out

    return lambda q, qd: pin.aba(model, data, config(q), qd, np.zeros(len(q)))


def _mujoco(text: str):
    import mujoco

    model = mujoco.MjModel.from_xml_string(text)
    data = mujoco.MjData(model)

    def qacc(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        data.qpos[:], data.qvel[:] = q, qd
        mujoco.mj_forward(model, data)
        return data.qacc.copy()

    return qacc


def rhs_table(n: int, rounds: int = 7) -> list[tuple[str, float, float]]:
    """(tool, µs per q̈, max |q̈ − Pinocchio|) at one random state."""
    import pfaff

    text = _urdf(n)
    q, qd = _state(n)
    path = os.path.join(tempfile.mkdtemp(), "arm.urdf")
    with open(path, "w") as f:
        f.write(text)
    system = pfaff.load_urdf(path)
    eom = system.equations()
    model = eom.compile(system.urdf_values)
    machine = eom.compile(system.urdf_values, evaluator="machine")
    ode, ode_machine = model.ode_function(), machine.ode_function()
    y = np.concatenate([q, qd])
    calls = {
        "pfaff accelerations": lambda: model.accelerations(0.0, q, qd)[0],
        f"pfaff ode ({model.evaluator})": lambda: np.asarray(ode(0.0, y))[n : 2 * n],
        "pfaff ode (machine)": lambda: np.asarray(ode_machine(0.0, y))[n : 2 * n],
        "pinocchio aba": lambda: aba(q, qd),
        "mujoco mj_forward": lambda: mj(q, qd),
    }
    aba = _pinocchio(text)
    mj = _mujoco(text)
    ref = aba(q, qd)
    times: dict[str, list[float]] = {k: [] for k in calls}
    for _ in range(rounds):
        for name, fn in calls.items():
            number = 200
            times[name].append(timeit.timeit(fn, number=number) / number * 1e6)
    return [
        (name, statistics.median(times[name]), float(np.abs(calls[name]() - ref).max()))
        for name in calls
    ]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--n", type=int, nargs="+", default=[3, 6, 12])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--timeout", type=float, default=600.0)
    p.add_argument("--child", choices=["pfaff", "kane"])
    p.add_argument("--rhs-only", action="store_true", help="only (ii), the right-hand sides")
    args = p.parse_args()
    if args.child:
        print(json.dumps(child(args.child, args.n[0])))
        return
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs\n")
    if not args.rhs_only:
        first_qdd(args)
    print("\n(ii) one right-hand side, µs (median of 7 interleaved rounds), max |qdd - pinocchio|")
    for n in args.n:
        for name, us, err in rhs_table(n):
            print(f"{n:>3} {name:<22} {us:>9.1f} {err:>10.1e}")


def first_qdd(args: argparse.Namespace) -> None:
    """Table (i)."""
    print("(i) model -> first qdd, cold process, wall s (medians)")
    print(f"{'n':>3} {'pfaff':>9} {'kane':>9} {'kane/pfaff':>11} {'max|dqdd|':>10}")
    for n in args.n:
        runs: dict[str, list] = {"pfaff": [], "kane": []}
        for _ in range(args.repeats):
            for tool in runs:
                if runs[tool] and runs[tool][-1] is None:
                    continue  # a timed-out tool is not run again
                runs[tool].append(_spawn(tool, n, args.timeout))
        pf = statistics.median(r["wall"] for r in runs["pfaff"])
        done = [r for r in runs["kane"] if r is not None]
        if done:
            kn = statistics.median(r["wall"] for r in done)
            diff = np.abs(np.array(done[0]["qdd"]) - runs["pfaff"][0]["qdd"]).max()
            print(f"{n:>3} {pf:>9.2f} {kn:>9.2f} {kn / pf:>11.1f} {diff:>10.1e}")
        else:
            print(f"{n:>3} {pf:>9.2f} {'>' + format(args.timeout, '.0f'):>9} {'-':>11} {'-':>10}")


if __name__ == "__main__":
    main()
