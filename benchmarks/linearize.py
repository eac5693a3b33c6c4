"""Benchmark: the Whipple bicycle linearized by pfaff (symbolic and numeric paths) and by SymPy.

The benchmark bicycle of Meijaard et al. (2007) about upright straight running at v = 5 m/s
(``pfaff.models.whipple_bicycle``), states (x, y, ψ, φ, θ_R, δ, θ_F, φ̇, θ̇_R, δ̇):

* pfaff, symbolic path: ``eom.linearize(op_point, independent, independent_speeds)``, cold (its
  derivatives made on the first call) and warm (a second speed);
* pfaff, numeric path: ``model.linearize(t, q, q̇, ...)`` of the compiled model: the first call
  (derivatives generated into code) and the median wall time of later calls, against the median
  of ``model.accelerations`` at the same state (the baseline);
* SymPy: ``KanesMethod.linearize(A_and_B=True)`` of the same bicycle built with ``KanesMethod``
  (``benchmarks/bicycle.py``, Cramer's rule for the dependent speeds), then evaluated at the same
  point with the parameter values.

Printed: CPU seconds of each (the equations' derivation excluded and shown apart), the largest
difference of the A matrices between each pair, and the largest difference of the lean-steer
eigenvalues from the published matrices. Run from the project root::

    python benchmarks/linearize.py [--speed 5] [--no-kane]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import pfaff
from pfaff.models.bicycle import (
    MEIJAARD,
    bicycle_state,
    lean_steer_eigenvalues,
    meijaard_eigenvalues,
)


def _cpu(fn):
    t0 = time.process_time()
    out = fn()
    return out, time.process_time() - t0


def kane_A(speed: float) -> tuple[np.ndarray, float, float]:
    """SymPy's A at ``speed``: (A, CPU s of the KanesMethod build, CPU s of linearize + numbers)."""
    import sympy as sp

    sys.path.insert(0, str(Path(__file__).parent))
    from bicycle import kane_bicycle

    (kane, q, u), build = _cpu(kane_bicycle)
    t0 = time.process_time()
    qv, uv = bicycle_state(MEIJAARD, speed=speed)
    op = dict(zip(q, qv, strict=True)) | dict(zip(u, uv, strict=True))
    op |= {ui.diff(): 0 for ui in u}  # the steady motion's accelerations (sympy#20486)
    A, _, _ = kane.linearize(op_point=op, A_and_B=True)
    A = np.array(A.subs({sp.Symbol(k): v for k, v in MEIJAARD.items()}).evalf(), dtype=float)
    return A, build, time.process_time() - t0


def _median_ms(fn, calls: int = 200) -> float:
    """Median wall time of ``fn()`` in ms over ``calls`` calls."""
    times = []
    for _ in range(calls):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=float, default=5.0)
    ap.add_argument("--no-kane", action="store_true", help="leave SymPy's linearization out")
    args = ap.parse_args()
    v = args.speed
    bike = pfaff.models.whipple_bicycle()
    ind, spd = bike.independent, bike.independent_speeds
    eom, t_eom = _cpu(bike.equations)
    op = bike.operating_point(v)
    lin_s, t_cold = _cpu(lambda: eom.linearize(op, ind, spd))
    _, t_warm = _cpu(lambda: eom.linearize(bike.operating_point(v + 1), ind, spd))
    model, t_compile = _cpu(lambda: eom.compile(MEIJAARD))
    q, qd = bicycle_state(MEIJAARD, speed=v)
    names = [str(c.func) for c in ind]
    speeds = [str(c.func) for c in spd]
    lin_n, t_num = _cpu(lambda: model.linearize(0.0, q, qd, names, speeds))
    ms_lin = _median_ms(lambda: model.linearize(0.0, q, qd, names, speeds))
    ms_acc = _median_ms(lambda: model.accelerations(0.0, q, qd))
    ref = meijaard_eigenvalues(v)
    print(f"Whipple bicycle at v = {v:g} m/s: 10 states (7 coordinates, 3 rates), CPU s")
    print(f"  pfaff equations()                         {t_eom:8.3f}")
    print(f"  pfaff eom.linearize, first (derivatives)  {t_cold:8.3f}")
    print(f"  pfaff eom.linearize, next speed           {t_warm:8.3f}")
    print(f"  pfaff compile()                           {t_compile:8.3f}")
    print(f"  pfaff model.linearize, first (codegen)    {t_num:8.3f}")
    print(f"  pfaff model.linearize, next calls (ms)    {ms_lin:8.3f}  (median wall time)")
    print(f"  pfaff model.accelerations, baseline (ms)  {ms_acc:8.3f}  (median wall time)")
    d_sn = np.abs(lin_s.A - lin_n.A).max()
    print(f"  max |A_symbolic - A_numeric|              {d_sn:8.1e}")
    err = np.abs(lean_steer_eigenvalues(lin_s) - ref).max()
    print(f"  lean-steer eigenvalues vs the published equations: max error {err:.1e}")
    if args.no_kane:
        return
    A_k, t_build, t_lin = kane_A(v)
    d_k = np.abs(A_k - lin_s.A).max()
    w_k = np.linalg.eigvals(A_k[np.ix_([3, 5, 7, 9], [3, 5, 7, 9])])
    w_k = w_k[np.lexsort((w_k.imag, w_k.real))]
    print(f"  SymPy KanesMethod build + kanes_equations {t_build:8.3f}")
    print(f"  SymPy KanesMethod.linearize + numbers     {t_lin:8.3f}")
    print(f"  max |A_pfaff - A_sympy|                   {d_k:8.1e}")
    print(f"  SymPy's lean-steer eigenvalues vs published: max error {np.abs(w_k - ref).max():.1e}")


if __name__ == "__main__":
    main()
