"""Benchmark: a general system (no family) from model to numbers, pfaff against SymPy.

The system is the planar n-link pendulum on a cart of
``sympy.physics.mechanics.models.n_link_pendulum_on_cart`` (cart force F, no joint torques), built
in pfaff as :func:`pfaff.models.n_link_pendulum_on_cart`. Per n one row, CPU seconds:

``pfaff``
    model + ``equations()`` + ``compile(values)`` + one ``accelerations`` call.
``kane``
    SymPy's model function (``KanesMethod`` and ``kanes_equations``) + ``lambdify(cse=True)`` of
    ``mass_matrix_full`` and ``forcing_full`` + one ``numpy.linalg.solve``.
``lagrange``
    ``LagrangesMethod`` on the same particles (``Lagrangian``, the push in ``forcelist``),
    ``form_lagranges_equations()`` + ``lambdify(cse=True)`` of ``mass_matrix`` and ``forcing`` +
    one solve (up to ``--lagrange-max``; it is the slow one).

then the ratio pfaff / kane (below 1: pfaff is faster) and the largest difference of q̈ between
pfaff and Kane at a random state (they must agree to 1e-9 relative). SymPy's cache is cleared
before every measurement. Then one right-hand side (q̈, and λ for pfaff) in µs: pfaff's compiled
model against the lambdified Kane mass matrix and forcing + ``numpy.linalg.solve``.

Run (from the project root)::

    python benchmarks/derive_general.py                 # n = 1, 2, 4, 6, 8, 10
    python benchmarks/derive_general.py --n 1 2 4 --lagrange-max 2
"""

from __future__ import annotations

import argparse
import gc
import os
import tempfile
import time
import timeit

import numpy as np
import sympy as sp
import sympy.physics.mechanics as me
from scipy.integrate import solve_ivp
from sympy.core.cache import clear_cache
from sympy.physics.mechanics.models import n_link_pendulum_on_cart

os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp()  # cold: pfaff's code cache starts empty

import pfaff


def _values(n: int, rng: np.random.Generator) -> dict[str, float]:
    vals = {f"m{i}": float(rng.uniform(0.5, 2.0)) for i in range(n + 1)}
    vals |= {f"l{i}": float(rng.uniform(0.5, 1.5)) for i in range(n)}
    return vals | {"g": 9.81, "F": 0.7}


def _fresh() -> float:
    clear_cache()
    gc.collect()
    return time.process_time()


def run_pfaff(n: int, vals: dict, q: np.ndarray, u: np.ndarray):
    t0 = _fresh()
    model = pfaff.models.n_link_pendulum_on_cart(n).equations().compile(vals)
    qdd, _ = model.accelerations(0.0, q, u)
    return time.process_time() - t0, qdd, model


def _lambdified(M, f, q, u, syms: list, F_t):
    args = [*q, *u, *syms]
    fM = sp.lambdify(args, M.subs(F_t, sp.Symbol("F")), modules="numpy", cse=True)
    ff = sp.lambdify(args, f.subs(F_t, sp.Symbol("F")), modules="numpy", cse=True)
    return fM, ff


def run_kane(n: int, vals: dict, q0: np.ndarray, u0: np.ndarray):
    t0 = _fresh()
    kane = n_link_pendulum_on_cart(n, cart_force=True, joint_torques=False)
    q, u = kane.q[:, 0], kane.u[:, 0]
    F_t = me.dynamicsymbols("F")
    names = [f"m{i}" for i in range(n + 1)] + [f"l{i}" for i in range(n)] + ["g", "F"]
    syms = [sp.Symbol(s) for s in names]
    fM, ff = _lambdified(kane.mass_matrix_full, kane.forcing_full, q, u, syms, F_t)
    p = [vals[s] for s in names]
    x = np.linalg.solve(fM(*q0, *u0, *p), np.ravel(ff(*q0, *u0, *p)))
    cpu = time.process_time() - t0
    rhs = lambda: np.linalg.solve(fM(*q0, *u0, *p), np.ravel(ff(*q0, *u0, *p)))  # noqa: E731
    return cpu, x[n + 1 :], rhs


def run_lagrange(n: int, vals: dict, q0: np.ndarray, u0: np.ndarray):
    t0 = _fresh()
    q = me.dynamicsymbols(f"q:{n + 1}")
    qd = [qi.diff(me.dynamicsymbols._t) for qi in q]
    m = sp.symbols(f"m:{n + 1}")
    length = sp.symbols(f"l:{n}")
    g, F = sp.symbols("g F")
    N = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(N, 0)
    P = origin.locatenew("P0", q[0] * N.x)
    P.set_vel(N, qd[0] * N.x)
    parts = [me.Particle("pa0", P, m[0])]
    loads = [(P, F * N.x - m[0] * g * N.y)]
    for i in range(1, n + 1):
        B = N.orientnew(f"B{i}", "Axis", [q[i], N.z])
        B.set_ang_vel(N, qd[i] * N.z)
        Pi = P.locatenew(f"P{i}", length[i - 1] * B.y)
        Pi.v2pt_theory(P, N, B)
        parts.append(me.Particle(f"pa{i}", Pi, m[i]))
        loads.append((Pi, -m[i] * g * N.y))
        P = Pi
    lm = me.LagrangesMethod(me.Lagrangian(N, *parts), q, forcelist=loads, frame=N)
    lm.form_lagranges_equations()
    syms = [*m, *length, g, F]
    qs = [sp.Symbol(f"_q{i}") for i in range(n + 1)]
    us = [sp.Symbol(f"_u{i}") for i in range(n + 1)]
    rep = {**dict(zip(qd, us, strict=True)), **dict(zip(q, qs, strict=True))}
    M, f = lm.mass_matrix.xreplace(rep), lm.forcing.xreplace(rep)
    fM = sp.lambdify([*qs, *us, *syms], M, modules="numpy", cse=True)
    ff = sp.lambdify([*qs, *us, *syms], f, modules="numpy", cse=True)
    names = [f"m{i}" for i in range(n + 1)] + [f"l{i}" for i in range(n)] + ["g", "F"]
    p = [vals[s] for s in names]
    x = np.linalg.solve(fM(*q0, *u0, *p), np.ravel(ff(*q0, *u0, *p)))
    return time.process_time() - t0, x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1, 2, 4, 6, 8, 10])
    ap.add_argument("--lagrange-max", type=int, default=8)
    ap.add_argument(
        "--simulate", type=int, default=8, help="chain length of the 10 s run (0: none)"
    )
    args = ap.parse_args()
    # lazy imports and first-call costs of both tools, untimed
    warm = _values(1, np.random.default_rng(0))
    run_pfaff(1, warm, np.zeros(2), np.zeros(2))
    run_kane(1, warm, np.zeros(2), np.zeros(2))
    print("n-link pendulum on a cart, pushed cart; CPU s from model to one q̈ (SymPy cache cleared)")
    head = f"{'n':>3} {'pfaff':>8} {'kane':>8} {'lagrange':>9} {'pfaff/kane':>11} {'|Δq̈| rel':>10}"
    print(head)
    print("-" * len(head))
    last = None
    ok = True
    for n in args.n:
        rng = np.random.default_rng(n)
        vals = _values(n, rng)
        q, u = rng.uniform(-1.0, 1.0, n + 1), rng.uniform(-1.0, 1.0, n + 1)
        tp, qdd, model = run_pfaff(n, vals, q, u)
        tk, qdd_k, rhs = run_kane(n, vals, q, u)
        lag = "-"
        if n <= args.lagrange_max:
            tl, qdd_l = run_lagrange(n, vals, q, u)
            lag = f"{tl:9.3f}"
            ok &= bool(np.allclose(qdd_l, qdd_k, rtol=1e-9, atol=1e-9))
        err = float(np.max(np.abs(qdd - qdd_k)) / max(1.0, np.max(np.abs(qdd_k))))
        ok &= err <= 1e-9
        print(f"{n:3d} {tp:8.3f} {tk:8.3f} {lag:>9} {tp / tk:11.2f} {err:10.1e}")
        last = (n, model, rhs, q, u)
    if last is not None:
        n, model, rhs, q, u = last
        y = np.concatenate([q, u])
        fun = model.ode_function()
        for name, fn in (
            ("pfaff q̈ + λ (accelerations)", lambda: model.accelerations(0.0, q, u)),
            ("pfaff ODE right-hand side", lambda: fun(0.0, y)),
            ("SymPy Kane lambdified + solve", rhs),
        ):
            k = 2000
            us = min(timeit.repeat(fn, number=k, repeat=3)) / k * 1e6
            print(f"one right-hand side, n = {n}: {name:32s} {us:9.1f} µs")
    print(f"accelerations agree with Kane (and Lagrange) to 1e-9: {'OK' if ok else 'FAIL'}")
    if args.simulate:
        simulate_chain(args.simulate)


def simulate_chain(n: int, t_end: float = 10.0, rtol: float = 1e-9, atol: float = 1e-11) -> None:
    """10 s of the n-link chain released at rest hanging, slightly bent: ``pfaff.simulate`` against
    ``solve_ivp(DOP853)`` on the lambdified Kane right-hand side, same tolerances (CPU s)."""
    rng = np.random.default_rng(0)
    vals = _values(n, rng)
    q0 = np.concatenate([[0.0], np.pi + rng.uniform(-0.05, 0.05, n)])  # hanging: not chaotic
    u0 = np.zeros(n + 1)
    model = pfaff.models.n_link_pendulum_on_cart(n).equations().compile(vals)
    kane = n_link_pendulum_on_cart(n, cart_force=True, joint_torques=False)
    q, u = kane.q[:, 0], kane.u[:, 0]
    names = [f"m{i}" for i in range(n + 1)] + [f"l{i}" for i in range(n)] + ["g", "F"]
    fM, ff = _lambdified(
        kane.mass_matrix_full, kane.forcing_full, q, u, [sp.Symbol(s) for s in names],
        me.dynamicsymbols("F"),
    )  # fmt: skip
    p = [vals[s] for s in names]

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        return np.linalg.solve(fM(*y, *p), np.ravel(ff(*y, *p)))

    t0 = time.process_time()
    ref = solve_ivp(
        rhs, (0.0, t_end), np.concatenate([q0, u0]), method="DOP853", rtol=rtol, atol=atol
    )
    t_ref = time.process_time() - t0
    traj = pfaff.simulate(model, q0, u0, (0.0, t_end), rtol=rtol, atol=atol, progress=False)
    t_pf = traj.stats["cpu_time"]
    err = float(np.max(np.abs(traj.q[-1] - ref.y[: n + 1, -1])))
    print(
        f"10 s of the {n}-link chain, DOP853 rtol={rtol:g}: solve_ivp on Kane {t_ref:.3f} s "
        f"({ref.nfev} nfev), pfaff.simulate {t_pf:.3f} s ({traj.stats['nfev']} nfev): "
        f"{t_ref / t_pf:.1f}x; end states differ by {err:.1e}"
    )
    cart = cartesian_chain(n)
    X, Y, qs, us = [0.0], [0.0], [0.0], [0.0]
    for i in range(1, n + 1):  # the same bent, resting shape in bob positions
        X.append(X[-1] - vals[f"l{i - 1}"] * np.sin(q0[i]))
        Y.append(Y[-1] + vals[f"l{i - 1}"] * np.cos(q0[i]))
        qs += [X[-1], Y[-1]]
        us += [0.0, 0.0]
    cm = cart.equations().compile(vals)
    tc = pfaff.simulate(cm, qs, us, (0.0, t_end), rtol=rtol, atol=atol, progress=False)
    f_max = float(np.abs(tc.position_residual).max())
    err = abs(float(tc.q[-1, 0]) - float(ref.y[0, -1]))
    print(
        f"the same chain in Cartesian coordinates ({cm.n} coordinates, {cm.m} rods, multipliers, "
        f"projection): {tc.stats['cpu_time']:.3f} s, {t_ref / tc.stats['cpu_time']:.1f}x "
        f"solve_ivp on Kane; max |f| {f_max:.1e}; cart position at the end differs by {err:.1e}"
    )


def cartesian_chain(n: int) -> pfaff.System:
    """The n-link pendulum on a cart in the bobs' Cartesian positions, with rod constraints."""
    x0, *xy = pfaff.coordinates("x0 " + " ".join(f"X{i} Y{i}" for i in range(1, n + 1)))
    m = sp.symbols(f"m0:{n + 1}")
    length = sp.symbols(f"l0:{n}")
    g, F = sp.symbols("g F")
    s = pfaff.System([x0, *xy], name=f"{n}-link Cartesian chain on a cart")
    s.add_particle(m[0], [x0, 0])
    s.add_generalized_force(x0, F)
    px, py = x0, sp.S.Zero
    for i in range(1, n + 1):
        X, Y = xy[2 * i - 2], xy[2 * i - 1]
        s.add_particle(m[i], [X, Y])
        s.add_potential_energy(m[i] * g * Y)
        s.add_holonomic_constraint(
            (X - px) ** 2 + (Y - py) ** 2 - length[i - 1] ** 2, name=f"rod{i}"
        )
        px, py = X, Y
    return s


if __name__ == "__main__":
    main()
