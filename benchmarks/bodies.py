"""Benchmark: rigid bodies, from model to numbers, pfaff against SymPy's KanesMethod.

(i) The torque-free body (:func:`pfaff.models.torque_free_body`, principal moments 1, 2, 3) with
each attitude set: CPU seconds of ``torque_free_body`` + ``equations()`` ("derive") and of
``compile()`` + the first ``accelerations`` call ("compile": the compiled code is generated
lazily, at the first call), then one ``accelerations`` call in µs (``timeit``, best of 5), and the
largest difference of the body's ω̇ from Euler's equations at a random state.

(ii) A spatial chain of N rigid rods (a chain of spherical pendulums): rod 1 hangs from a fixed
point, rod i+1 from the bottom end of rod i, each a uniform solid cylinder of mass m, length l and
radius a (the slender body's axis is its body z axis), under gravity. Per N one row, CPU seconds:

``pfaff``
    ``System`` build (each rod's attitude a :class:`~pfaff.attitude.Quaternion`, its mass
    centre's position written through the DCMs of the rods above it: 4N coordinates, N unit-norm
    constraints) + ``equations()`` + ``compile(values)`` + one ``accelerations`` call.
``kane``
    ``sympy.physics.mechanics``: each rod's frame oriented by body-fixed 1-2-3 angles
    (``orient_body_fixed``, 3N coordinates), the generalized speeds its body-frame angular
    velocity components, mass centre and end points by ``v2pt_theory``; ``KanesMethod`` +
    ``kanes_equations`` + ``lambdify(cse=True)`` of ``mass_matrix_full`` and ``forcing_full`` +
    one ``numpy.linalg.solve``.

then the ratio pfaff / kane (below 1: pfaff is faster) and the largest difference of the rods' ω̇
(body components: frame-independent, the bodies' axes are the same in both models) at the same
random physical state. Each measurement runs in a fresh process (first-call costs of both tools
paid there untimed, SymPy's cache cleared, pfaff's code cache a new empty folder); a SymPy run
that exceeds ``--timeout`` CPU-and-wall seconds (120) is killed and SymPy is not run on longer
chains.

Run (from the project root)::

    python benchmarks/bodies.py                         # N = 1, 2, 4, 8, 16 (a few minutes)
    python benchmarks/bodies.py --n 1 2 4 8 16 32 64    # the long sweep
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import subprocess
import sys
import tempfile
import time
import timeit

import numpy as np

VALUES = {"m": 0.7, "l": 0.9, "a": 0.05, "g": 9.81}


def _fresh_cache() -> None:
    """A new, empty pfaff code cache (read at compile time)."""
    os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="pfaff-bench-")


def _fresh() -> float:
    from sympy.core.cache import clear_cache

    _fresh_cache()
    clear_cache()
    gc.collect()
    return time.process_time()


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    m, n = (axis + 1) % 3, (axis + 2) % 3
    r = np.eye(3)
    r[m, m], r[m, n], r[n, m], r[n, n] = c, -s, s, c
    return r


def chain_state(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The physical state compared: per rod body-fixed 1-2-3 angles (its DCM is
    R1(a) R2(b) R3(c), r_inertial = C r_body) and body angular velocity, shape (n, 3) each."""
    rng = np.random.default_rng(100 + n)
    return rng.uniform(-0.6, 0.6, (n, 3)), rng.uniform(-1.0, 1.0, (n, 3))


def dcm_123(angles: np.ndarray) -> np.ndarray:
    return _rot(0, angles[0]) @ _rot(1, angles[1]) @ _rot(2, angles[2])


# ---------------------------------------------------------------------------------------------
# (i) the torque-free body
# ---------------------------------------------------------------------------------------------


def torque_free(kind: str, rng: np.random.Generator) -> tuple[float, float, float, float]:
    """(derive s, compile + first call s, one call µs, max |ω̇ − Euler|) of one attitude set."""
    import sympy as sp

    import pfaff

    inertia = np.array([1.0, 2.0, 3.0])
    t0 = _fresh()
    system = pfaff.models.torque_free_body(kind)
    eom = system.equations()
    derive = time.process_time() - t0
    att = system.bodies[0].attitude  # the state, untimed (the numeric helpers lambdify too)
    w = rng.uniform(-2.0, 2.0, 3)
    q = att.from_dcm(dcm_123(rng.uniform(-1.0, 1.0, 3)))
    qd = att.rates(q, w)
    t1 = time.process_time()
    model = eom.compile({"I1": inertia[0], "I2": inertia[1], "I3": inertia[2]})
    qdd, _ = model.accelerations(0.0, q, qd)
    compile_ = time.process_time() - t1
    us = min(timeit.repeat(lambda: model.accelerations(0.0, q, qd), number=2000, repeat=5))
    # ω̇ = d/dt (B(q) q̇), from the attitude's own ω(q, q̇), against Euler's equations
    n = len(att.coordinates)
    xs, xds, xdds = sp.symbols(f"x:{n}"), sp.symbols(f"xd:{n}"), sp.symbols(f"xdd:{n}")
    rep = {c.diff(pfaff.t, 2): s for c, s in zip(att.coordinates, xdds, strict=True)}
    rep |= {c.diff(pfaff.t): s for c, s in zip(att.coordinates, xds, strict=True)}
    rep |= dict(zip(att.coordinates, xs, strict=True))
    wdot = sp.lambdify([*xs, *xds, *xdds], att.angular_velocity.diff(pfaff.t).xreplace(rep))
    got = np.ravel(wdot(*q, *qd, *qdd))
    I1, I2, I3 = inertia
    euler = [
        (I2 - I3) * w[1] * w[2] / I1,
        (I3 - I1) * w[2] * w[0] / I2,
        (I1 - I2) * w[0] * w[1] / I3,
    ]
    return derive, compile_, us / 2000 * 1e6, float(np.abs(got - euler).max())


# ---------------------------------------------------------------------------------------------
# (ii) the chain, one tool per process
# ---------------------------------------------------------------------------------------------


def pfaff_chain(n: int):
    """The chain as a pfaff System: rod i's attitude Quaternion(b{i}_0:4)."""
    import sympy as sp

    import pfaff
    from pfaff.attitude import Quaternion

    m, length, a, g = sp.symbols("m l a g")
    betas = [pfaff.coordinates(" ".join(f"b{i}_{k}" for k in range(4))) for i in range(1, n + 1)]
    s = pfaff.System([c for b in betas for c in b], name=f"chain of {n} rods")
    end = sp.zeros(3, 1)  # the fixed point, then each rod's bottom end
    transverse, axial = m * (3 * a**2 + length**2) / 12, m * a**2 / 2
    for i, beta in enumerate(betas, 1):
        att = Quaternion(beta)
        axis = att.dcm[:, 2]  # the rod's body z axis in inertial components
        centre = end - length / 2 * axis
        s.add_rigid_body(m, [transverse, transverse, axial], list(centre), att, name=f"rod{i}")
        s.add_potential_energy(m * g * centre[2], name=f"gravity{i}")
        end = end - length * axis
    return s


def run_pfaff(n: int) -> dict:
    import pfaff
    from pfaff.attitude import Quaternion

    def once(n: int) -> tuple[float, float, np.ndarray]:
        angles, omegas = chain_state(n)
        att = Quaternion(pfaff.coordinates("c0:4"))  # numeric helpers only
        betas = [att.from_dcm(dcm_123(a)) for a in angles]
        q = np.concatenate(betas)
        qd = np.concatenate([att.rates(b, w) for b, w in zip(betas, omegas, strict=True)])
        t0 = _fresh()
        model = pfaff_chain(n).equations().compile(VALUES)
        t1 = time.process_time()
        qdd, _ = model.accelerations(0.0, q, qd)
        t2 = time.process_time()
        res = np.abs(np.concatenate(model.constraint_residual(0.0, q, qd))).max()
        assert res < 1e-12, res
        wdot = []
        for i in range(n):  # ω̇ = 2 (β0 v̈ − β̈0 v − v × v̈)
            b, bdd = q[4 * i : 4 * i + 4], qdd[4 * i : 4 * i + 4]
            wdot.append(2 * (b[0] * bdd[1:] - bdd[0] * b[1:] - np.cross(b[1:], bdd[1:])))
        return t2 - t0, t2 - t1, np.array(wdot)

    once(1)  # first-call costs, untimed
    cpu, first, wdot = once(n)
    return {"cpu": cpu, "first_call": first, "wdot": wdot.tolist()}


def run_kane(n: int) -> dict:
    import sympy as sp
    import sympy.physics.mechanics as me

    def once(n: int) -> tuple[float, np.ndarray]:
        angles, omegas = chain_state(n)
        t0 = _fresh()
        m, length, a, g = sp.symbols("m l a g")
        N = me.ReferenceFrame("N")
        end = me.Point("O")
        end.set_vel(N, 0)
        transverse, axial = m * (3 * a**2 + length**2) / 12, m * a**2 / 2
        bodies, loads, kd, qs, us, frames = [], [], [], [], [], []
        for i in range(1, n + 1):
            q = me.dynamicsymbols(f"q{i}_1:4")
            u = me.dynamicsymbols(f"u{i}_1:4")
            B = me.ReferenceFrame(f"B{i}")
            B.orient_body_fixed(N, q, "123")
            w = B.ang_vel_in(N)
            kd += [me.dot(w, B.x) - u[0], me.dot(w, B.y) - u[1], me.dot(w, B.z) - u[2]]
            B.set_ang_vel(N, u[0] * B.x + u[1] * B.y + u[2] * B.z)
            G = end.locatenew(f"G{i}", -length / 2 * B.z)
            G.v2pt_theory(end, N, B)
            bottom = end.locatenew(f"P{i}", -length * B.z)
            bottom.v2pt_theory(end, N, B)
            inertia = (me.inertia(B, transverse, transverse, axial), G)
            bodies.append(me.RigidBody(f"rod{i}", G, B, m, inertia))
            loads.append((G, -m * g * N.z))
            end = bottom
            qs += q
            us += u
            frames.append(B)
        kane = me.KanesMethod(N, q_ind=qs, u_ind=us, kd_eqs=kd)
        kane.kanes_equations(bodies, loads)
        args = [*qs, *us, *sp.symbols("m l a g")]
        f_M = sp.lambdify(args, kane.mass_matrix_full, modules="numpy", cse=True)
        f_f = sp.lambdify(args, kane.forcing_full, modules="numpy", cse=True)
        x = [*np.ravel(angles), *np.ravel(omegas), *(VALUES[k] for k in "mlag")]
        sol = np.linalg.solve(f_M(*x), np.ravel(f_f(*x)))
        cpu = time.process_time() - t0
        if n <= 2:  # the angles mean what chain_state says
            for B, ang in zip(frames, angles, strict=True):
                rep = dict(zip(qs, np.ravel(angles), strict=True))
                C = np.array(N.dcm(B).xreplace(rep).evalf(), dtype=float)
                assert np.abs(C - dcm_123(ang)).max() < 1e-14
        return cpu, sol[3 * n :].reshape(n, 3)  # u̇ = ω̇ in body components

    once(1)  # first-call costs, untimed
    cpu, wdot = once(n)
    return {"cpu": cpu, "wdot": wdot.tolist()}


def measure(tool: str, n: int, timeout: float | None) -> dict | None:
    """One measurement in a fresh process; None when it was killed at ``timeout`` s."""
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", tool, "--n", str(n)]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=True)
    except subprocess.TimeoutExpired:
        return None  # subprocess.run has killed it
    except subprocess.CalledProcessError as exc:
        raise RuntimeError(f"{tool} N={n} failed:\n{exc.stderr[-3000:]}") from exc
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    ap.add_argument("--timeout", type=float, default=120.0, help="SymPy's limit per N (s)")
    ap.add_argument("--pfaff-timeout", type=float, default=1800.0, help="pfaff's limit per N (s)")
    ap.add_argument("--worker", choices=["pfaff", "kane"], help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        run = run_pfaff if args.worker == "pfaff" else run_kane
        print(json.dumps(run(args.n[0])))
        return

    import pfaff

    print("(i) torque-free body, I = (1, 2, 3); CPU s (SymPy cache cleared, empty code cache)")
    head = f"{'attitude':>12} {'derive':>8} {'compile':>8} {'accel µs':>9} {'|ω̇−Euler|':>11}"
    print(head)
    print("-" * len(head))
    torque_free("quaternion", np.random.default_rng(0))  # first-call costs, untimed
    for kind in pfaff.models.bodies.ATTITUDES:
        d, c, us, err = torque_free(kind, np.random.default_rng(1))
        print(f"{kind:>12} {d:8.3f} {c:8.3f} {us:9.1f} {err:11.1e}")

    print()
    print(
        "(ii) chain of N rods hanging from a fixed point; CPU s from model to one acceleration"
        f" (SymPy killed after {args.timeout:g} s)"
    )
    head = f"{'N':>3} {'pfaff':>9} {'1st call':>9} {'kane':>9} {'pfaff/kane':>11} {'|Δω̇|':>9}"
    print(head)
    print("-" * len(head))
    sympy_on = True
    agree = True
    for n in args.n:
        pf = measure("pfaff", n, args.pfaff_timeout)
        kn = measure("kane", n, args.timeout) if sympy_on else None
        kane_txt = "-" if not sympy_on else f">{args.timeout:g}"
        ratio = err_txt = "-"
        if kn is not None:
            kane_txt = f"{kn['cpu']:9.3f}"
        elif sympy_on:
            sympy_on = False  # longer chains would take longer still
        if pf is None:
            pf_txt = first_txt = f">{args.pfaff_timeout:g}"
        else:
            pf_txt, first_txt = f"{pf['cpu']:9.3f}", f"{pf['first_call']:9.3f}"
        if pf is not None and kn is not None:
            ratio = f"{pf['cpu'] / kn['cpu']:11.2f}"
            err = float(np.abs(np.array(pf["wdot"]) - np.array(kn["wdot"])).max())
            err_txt = f"{err:9.1e}"
            agree &= err < 1e-9
        elif n <= 2:
            agree = False  # N = 1, 2 must be compared
        print(f"{n:3d} {pf_txt:>9} {first_txt:>9} {kane_txt:>9} {ratio:>11} {err_txt:>9}")
    print(f"ω̇ of pfaff and Kane agree to 1e-9 where both ran: {'OK' if agree else 'FAIL'}")


if __name__ == "__main__":
    main()
