"""Benchmark: the Whipple bicycle of Meijaard et al. (2007), pfaff against SymPy's KanesMethod.

The benchmark bicycle of J. P. Meijaard, J. M. Papadopoulos, A. Ruina and A. L. Schwab,
"Linearized dynamics equations for the balance and steer of a bicycle: a benchmark and review",
Proc. R. Soc. A 463 (2007) 1955-1982: four rigid bodies (rear wheel R, rear frame with rider B,
front fork and handlebar H, front wheel F), knife-edge wheels rolling without slip on flat
ground. Eight coordinates, in Meijaard's axes (x forward, y right, z down):

    q = (x, y, ψ, φ, θ_R, θ_B, δ, θ_F)

the rear contact point (x, y), yaw ψ, lean (roll) φ, the rear wheel's rotation θ_R relative to
the frame, the frame's pitch θ_B, steer δ and the front wheel's rotation θ_F relative to the fork;
four nonholonomic no-slip constraints (both contact points, in the ground plane) and one holonomic
one (the front wheel touches the ground), so three degrees of freedom at the velocity level.

:func:`pfaff.models.whipple_bicycle` (imported here as :func:`whipple_bicycle`) builds it in pfaff: the kinetic energy of each body from
``sympy.physics.mechanics`` frames and points (an expression in q and q̇), gravity as a potential,
the contact constraints with ``add_velocity_constraint`` / ``add_holonomic_constraint``.
:func:`kane_bicycle` builds the same bicycle from the same kinematics the standard way with
``KanesMethod`` (u = q̇, the pitch dependent with the configuration constraint, the speeds of x, y,
ψ, θ_B, θ_F dependent with five velocity constraints, as in SymPy's ``test_kane3.py``).

Run (from the project root)::

    python benchmarks/bicycle.py               # cold CPU seconds, one fresh process per tool
    python benchmarks/bicycle.py --repeat 3    # best of three fresh processes per tool

Printed: CPU seconds from nothing to a numeric model (pfaff: ``System`` build + ``equations()`` +
``compile(values)``, the on-disk code cache off; Kane: build + ``kanes_equations`` +
``lambdify(cse=True)`` of ``mass_matrix_full`` and ``forcing_full``), each in a fresh subprocess
with SymPy's cache cleared, one BLAS thread, and the imports (and first-call costs, on a pendulum)
excluded; the CPU seconds of pfaff's first ``ode_function()`` call (where its machine-code
right-hand side is made); one right-hand side in CPU µs (timeit, best of several): pfaff's
``accelerations`` (checked, q̈ and λ), ``solve`` (unchecked, q̈ and λ) and ``ode_function`` (q̇ and
q̈ only) against the lambdified Kane matrices + ``numpy.linalg.solve``; and the largest relative
difference of q̈ between pfaff and Kane at three random states that satisfy the constraints.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import subprocess
import sys
import time
import timeit

import numpy as np
import sympy as sp
import sympy.physics.mechanics as me
from sympy.core.cache import clear_cache

import pfaff

# The model, its benchmark values and the published linearized equations live in the zoo.
from pfaff.models.bicycle import (
    COORDINATES,
    MEIJAARD,
    MEIJAARD_C1,
    MEIJAARD_CAPSIZE_SPEED,
    MEIJAARD_K0,
    MEIJAARD_K2,
    MEIJAARD_M,
    MEIJAARD_WEAVE_SPEED,
    bicycle_kinematics,
    bicycle_state,
    meijaard_lean_steer,
    whipple_bicycle,
)

__all__ = [
    "COORDINATES",
    "MEIJAARD",
    "MEIJAARD_C1",
    "MEIJAARD_CAPSIZE_SPEED",
    "MEIJAARD_K0",
    "MEIJAARD_K2",
    "MEIJAARD_M",
    "MEIJAARD_WEAVE_SPEED",
    "bicycle_kinematics",
    "bicycle_state",
    "kane_accelerations",
    "kane_bicycle",
    "lean_steer_matrix",
    "meijaard_lean_steer",
    "random_state",
    "whipple_bicycle",
]


# --------------------------------------------------------------------------- Kane
def kane_bicycle() -> tuple[me.KanesMethod, list, list]:
    """The same bicycle with SymPy's ``KanesMethod``: u = q̇, θ_B and five speeds dependent.

    Independent speeds: lean, rear wheel and steer rates. The velocity constraints are the rear
    contact's x, y and the front contact's x, y, z components (the last one is the derivative of
    the holonomic constraint, the configuration constraint here). Returns ``(kane, q, u)`` after
    ``kanes_equations``; ``kane.q`` and ``kane.u`` list the independent ones first.

    The dependent speeds are solved for by Cramer's rule, as in ``test_kane3.py``. SymPy's default
    (``constraint_solver="LU"``, elimination in the given row order) takes as its fourth pivot an
    expression that vanishes wherever the front wheel touches the ground (1e-14 at a consistent
    state, 10.6 away from one): its equations are then wrong at every consistent state.
    """
    q = me.dynamicsymbols(COORDINATES)
    u = me.dynamicsymbols(" ".join(f"u_{s}" for s in COORDINATES.split()))
    kin = bicycle_kinematics(q, u)
    Y = kin["Y"]
    v_rear, v_front = kin["v_rear"], kin["v_front"]
    independent, pitch = (3, 4, 6), 5
    kane = me.KanesMethod(
        kin["N"],
        q_ind=[qi for i, qi in enumerate(q) if i != pitch],
        u_ind=[u[i] for i in independent],
        kd_eqs=[qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(q, u, strict=True)],
        q_dependent=[q[pitch]],
        configuration_constraints=[kin["holonomic"]],
        u_dependent=[ui for i, ui in enumerate(u) if i not in independent],
        velocity_constraints=[
            me.dot(v_rear, Y.x),
            me.dot(v_rear, Y.y),
            me.dot(v_front, Y.x),
            me.dot(v_front, Y.y),
            me.dot(v_front, Y.z),
        ],
        constraint_solver="CRAMER",  # as test_kane3; the default LU picks a pivot that is 0
    )
    gravity = [(b.masscenter, b.mass * kin["g"] * Y.z) for b in kin["bodies"]]
    kane.kanes_equations(kin["bodies"], gravity)
    return kane, q, u


def kane_accelerations(kane: me.KanesMethod, q: list, u: list, values: dict):
    """``rhs(q, q̇) -> q̈`` from ``lambdify(cse=True)`` of Kane's full mass matrix and forcing.

    ``q`` and ``q̇`` in the order of ``q`` and ``u`` given (:data:`COORDINATES`); Kane's own
    order (independent first) is undone on the way out.
    """
    names = list(MEIJAARD)
    args = [*q, *u, *(sp.Symbol(s) for s in names)]
    fM = sp.lambdify(args, kane.mass_matrix_full, modules="numpy", cse=True)
    ff = sp.lambdify(args, kane.forcing_full, modules="numpy", cse=True)
    p = [float(values[s]) for s in names]
    n = len(q)
    order = [list(kane.u).index(ui) for ui in u]  # Kane orders u independent first

    def rhs(qv: np.ndarray, qdv: np.ndarray) -> np.ndarray:
        x = np.linalg.solve(fM(*qv, *qdv, *p), np.ravel(ff(*qv, *qdv, *p)))
        return x[n:][order]

    return rhs


# --------------------------------------------------------------------------- states
def random_state(values: dict, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random consistent state: leaning, steered, rolling forward at 1 to 5 m/s."""
    return bicycle_state(
        values,
        phi=rng.uniform(-0.4, 0.4),
        delta=rng.uniform(-0.6, 0.6),
        phi_dot=rng.uniform(-1.0, 1.0),
        delta_dot=rng.uniform(-1.0, 1.0),
        speed=rng.uniform(1.0, 5.0),
        x=rng.uniform(-1.0, 1.0),
        y=rng.uniform(-1.0, 1.0),
        psi=rng.uniform(-np.pi, np.pi),
        theta_r=rng.uniform(-np.pi, np.pi),
        theta_f=rng.uniform(-np.pi, np.pi),
    )


def lean_steer_matrix(accelerations, values: dict, speed: float, h: float = 1e-5) -> np.ndarray:
    """∂(φ̈, δ̈)/∂(φ, δ, φ̇, δ̇) about upright straight running at ``speed`` (central differences).

    ``accelerations(q, q̇) -> q̈``. Meijaard's linearized equations give
    -M⁻¹ [g K0 + v² K2, v C1] for it.
    """
    names = ("phi", "delta", "phi_dot", "delta_dot")
    J = np.empty((2, 4))
    for j, name in enumerate(names):
        plus = accelerations(*bicycle_state(values, speed=speed, **{name: h}))
        minus = accelerations(*bicycle_state(values, speed=speed, **{name: -h}))
        J[:, j] = (plus[[3, 6]] - minus[[3, 6]]) / (2 * h)
    return J


# --------------------------------------------------------------------------- measurements
def _fresh() -> float:
    clear_cache()
    gc.collect()
    return time.process_time()


def _best_us(fn, number: int = 200, repeat: int = 5) -> float:
    """CPU µs of one call, best of ``repeat`` (CPU time: robust on a loaded machine)."""
    runs = timeit.repeat(fn, number=number, repeat=repeat, timer=time.process_time)
    return min(runs) / number * 1e6


def _warm_up() -> None:
    """First-call costs (lazy imports) of both tools on a pendulum, untimed."""
    pendulum = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    pendulum.ode_function()(0.0, np.array([0.1, 0.0]))
    th, u = me.dynamicsymbols("th u")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    A.set_ang_vel(N, u * N.z)
    pivot = me.Point("pivot")
    pivot.set_vel(N, 0)
    bob = pivot.locatenew("bob", A.x)
    bob.v2pt_theory(pivot, N, A)
    km = me.KanesMethod(N, [th], [u], kd_eqs=[th.diff() - u])
    km.kanes_equations([me.Particle("p", bob, 1)], [(bob, -9.81 * N.y)])
    sp.lambdify([th, u], km.mass_matrix_full, cse=True)
    sp.lambdify([th, u], km.forcing_full, cse=True)


def measure(tool: str, states: list) -> dict:
    """One cold run of ``tool`` ("pfaff" or "kane") in this process, then q̈ and λ at ``states``
    ([(q, q̇), …]) and the µs of one right-hand side at the first."""
    _warm_up()
    values = MEIJAARD
    out: dict = {}
    if tool == "pfaff":
        t0 = _fresh()
        bike = whipple_bicycle()
        t1 = time.process_time()
        eom = bike.equations()
        t2 = time.process_time()
        model = eom.compile(values)
        t3 = time.process_time()
        out |= {"build": t1 - t0, "equations": t2 - t1, "compile": t3 - t2, "total": t3 - t0}
        results = [model.accelerations(0.0, q, qd) for q, qd in states]
        out["qdd"] = [r[0].tolist() for r in results]
        out["lambda"] = [r[1].tolist() for r in results]
        q, qd = (np.asarray(a) for a in states[0])
        y = np.concatenate([q, qd])
        t4 = time.process_time()
        fun = model.ode_function()  # the machine-code right-hand side is made here
        fun(0.0, y)
        out["ode_function"] = time.process_time() - t4
        out["us"] = {
            "accelerations": _best_us(lambda: model.accelerations(0.0, q, qd)),
            "solve": _best_us(lambda: model.solve(0.0, q, qd)),
            "ode_function": _best_us(lambda: fun(0.0, y)),
        }
    else:
        t0 = _fresh()
        kane, qs, us = kane_bicycle()
        t1 = time.process_time()
        rhs = kane_accelerations(kane, qs, us, values)
        t2 = time.process_time()
        out |= {"build": t1 - t0, "lambdify": t2 - t1, "total": t2 - t0}
        out["qdd"] = [rhs(np.asarray(q), np.asarray(qd)).tolist() for q, qd in states]
        q, qd = (np.asarray(a) for a in states[0])
        out["us"] = {"lambdified + solve": _best_us(lambda: rhs(q, qd))}
    return out


def _run(tool: str, states: list) -> dict:
    """:func:`measure` in a fresh Python process (pfaff's on-disk code cache off; one BLAS
    thread: matrices of 13 and 16 rows gain nothing from threads, and on a busy machine the
    waiting threads cost 10-50x per solve)."""
    threads = {v: "1" for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    env = os.environ | {"PFAFF_CACHE": "0"} | threads
    done = subprocess.run(
        [sys.executable, __file__, "--measure", tool],
        input=json.dumps([[q.tolist(), qd.tolist()] for q, qd in states]),
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    if done.returncode:
        raise RuntimeError(f"the {tool} run failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1, help="fresh processes per tool (best)")
    ap.add_argument("--states", type=int, default=3, help="random consistent states compared")
    ap.add_argument("--seed", type=int, default=2007)
    ap.add_argument("--measure", choices=("pfaff", "kane"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.measure:
        states = [(np.array(q), np.array(qd)) for q, qd in json.loads(sys.stdin.read())]
        print(json.dumps(measure(args.measure, states)))
        return
    rng = np.random.default_rng(args.seed)
    states = [random_state(MEIJAARD, rng) for _ in range(args.states)]
    runs = {tool: [_run(tool, states) for _ in range(args.repeat)] for tool in ("pfaff", "kane")}
    pf = min(runs["pfaff"], key=lambda r: r["total"])
    kn = min(runs["kane"], key=lambda r: r["total"])
    errs = [
        float(np.max(np.abs(np.subtract(a, b))) / np.max(np.abs(b)))
        for a, b in zip(pf["qdd"], kn["qdd"], strict=True)
    ]
    print(
        "Whipple bicycle (Meijaard et al. 2007): 8 coordinates, 4 nonholonomic + 1 holonomic "
        f"constraint; cold CPU s, fresh process, best of {args.repeat}"
    )
    width = 40
    print(f"{'':{width}} {'pfaff':>9} {'kane':>9} {'pfaff/kane':>11}")
    rows = [
        ("model to numeric model (s)", pf["total"], kn["total"]),
        ("  build: System / KanesMethod (s)", pf["build"], kn["build"]),
        ("  equations() (s)", pf["equations"], None),
        ("  compile() / lambdify (s)", pf["compile"], kn["lambdify"]),
        ("first ode_function() call (s)", pf["ode_function"], None),
    ]
    k_us = kn["us"]["lambdified + solve"]
    rows += [(f"one right-hand side, {name} (µs)", us, k_us) for name, us in pf["us"].items()]
    for label, a, b in rows:
        fmt = ".3f" if label.endswith("(s)") else ".1f"
        kane, ratio = ("-", "") if b is None else (f"{b:{fmt}}", f"{a / b:.3f}")
        print(f"{label:{width}} {a:9{fmt}} {kane:>9} {ratio:>11}")
    print(
        f"max relative |Δq̈| pfaff vs Kane over {len(states)} consistent states: {max(errs):.1e} "
        f"({', '.join(f'{e:.1e}' for e in errs)}): {'OK' if max(errs) <= 1e-9 else 'FAIL'}"
    )
    if max(errs) > 1e-9:
        sys.exit(1)


if __name__ == "__main__":
    main()
