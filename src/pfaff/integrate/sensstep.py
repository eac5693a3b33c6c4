"""The projection method carrying forward sensitivities: the augmented ODE and its stepper.

The state y = [q, q̇] is integrated with the sensitivity matrices S = [S_q; S_v] (2n, k):
``AugmentedField`` solves the KKT system once per evaluation for q̈ and λ and once more, with the
same LU factorization, for ∂q̈/∂p and ∂λ/∂p (the variational equations of
:mod:`pfaff.derive.variational`). ``SensitivityRK`` is DOP853 on [y, vec S] whose error estimate
reads the state only (the sensitivities are left out of the step-size control: the steps are
chosen as a plain run's), and after every accepted step projects the state like ``"projection"`` and the
sensitivities onto the tangent of the constraint manifold at the projected state
(:func:`tangent_project`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pfaff.derive.variational import VariationalKernel
from pfaff.integrate.integrators import ProjectedRK
from pfaff.integrate.stepper import Power, StepperOptions, _RunFailure
from pfaff.numeric.projection import Projector
from pfaff.numeric.protocol import DynamicsModel


def tangent_project(kernel: VariationalKernel, x: np.ndarray, S: np.ndarray) -> np.ndarray:
    """S (2n, k) moved onto the tangent of the constraint manifold at the state in ``x``.

    The smallest (Euclidean) corrections such that f_q S_q + f_p = 0 on the holonomic rows and
    then V_q S_q + A S_v + V_p = 0 on every row (V = A q̇ + b); f_p, V_p are zero on the columns
    of initial values (those beyond ``kernel.n_p``).
    """
    n, r = kernel.n, kernel.n_p
    if not kernel.m:
        return S
    A, V_q, V_p, f_p = kernel.tangent(x)
    S = S.copy()
    Sq, Sv = S[:n], S[n:]
    hol = kernel.holonomic_rows
    if hol:
        res = A[hol] @ Sq
        res[:, :r] += f_p
        Sq -= np.linalg.lstsq(A[hol], res, rcond=None)[0]
    res = V_q @ Sq + A @ Sv
    res[:, :r] += V_p
    Sv -= np.linalg.lstsq(A, res, rcond=None)[0]
    return S


@dataclass
class SensitivitySetup:
    """What a sensitivity run needs beyond the state (made by :func:`pfaff.sensitivities`).

    ``S0`` (2n, k): the initial sensitivities, k = n_p (+ 2n initial columns); ``keep``: the
    constraint rows solved for (independent ones); ``report_steps``: the run reports step ends
    (no ``t_eval``). The stepper fills ``records`` {t: S} and ``stepper``.
    """

    kernel: VariationalKernel
    S0: np.ndarray
    keep: np.ndarray
    report_steps: bool
    t0: float
    records: dict[float, np.ndarray] = field(default_factory=dict)
    stepper: Any = None


class AugmentedField:
    """d/dt [q, q̇, vec S_q, vec S_v] = [q̇, q̈, vec S_v, vec S_a] for y of shape (2n + 2nk,)."""

    def __init__(self, setup: SensitivitySetup, p: np.ndarray) -> None:
        kern = setup.kernel
        self.kernel = kern
        self.n, self.m, self.r = n, m, r = kern.n, kern.m, kern.n_p
        self.k = k = setup.S0.shape[1]
        keep = np.asarray(setup.keep)
        # the rows of the KKT system solved: [q̈ rows, kept constraint rows] (all: a slice)
        self.rows = slice(None) if len(keep) == m else np.concatenate((np.arange(n), n + keep))
        self.keep = keep
        self.x = np.concatenate(([0.0], np.zeros(3 * n + m), p))
        # [S_q; S_v; P]: P (n_p, k) the identity on the parameters' columns (the ∂/∂p terms)
        self.ext = np.zeros((2 * n + r, k))
        self.ext[2 * n :, :r] = np.eye(r)
        self.nfev = 0
        from scipy.linalg.lapack import dgetrf, dgetrs  # (LAPACK directly: little overhead)

        self._lapack = dgetrf, dgetrs

    def solve(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any]:
        """q̈ (n,), S_a (n, k), S_λ (m, k) at (t, y) and λ (m,)."""
        n, m, k, x, rows = self.n, self.m, self.k, self.x, self.rows
        x[0] = t
        x[1 : 1 + 2 * n] = y[: 2 * n]
        x[1 + 2 * n : 1 + 3 * n + m] = 0.0
        K, EG = self.kernel.kkt(x)
        if m != len(self.keep):
            K, EG = K[np.ix_(rows, rows)], EG[rows]
        dgetrf, dgetrs = self._lapack
        lu, piv, info = dgetrf(K)  # one factorization for both solves
        if info > 0:
            raise np.linalg.LinAlgError(
                f"the KKT matrix of the sensitivities is singular at t = {t:.17g}"
            )
        sol = dgetrs(lu, piv, -EG)[0]
        lam = np.zeros(m)
        lam[self.keep] = -sol[n:]
        x[1 + 2 * n : 1 + 3 * n] = sol[:n]
        x[1 + 3 * n : 1 + 3 * n + m] = lam
        J = self.kernel.rates(x)
        ext = self.ext
        ext[: 2 * n] = y[2 * n :].reshape(2 * n, k)
        Z = dgetrs(lu, piv, -(J[rows] @ ext))[0]
        S_lam = np.zeros((m, k))
        S_lam[self.keep] = -Z[n:]
        return sol[:n], Z[:n], S_lam, lam

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        self.nfev += 1
        n, k = self.n, self.k
        qdd, Sa, _, _ = self.solve(t, y)
        out = np.empty_like(y)
        out[:n], out[n : 2 * n] = y[n : 2 * n], qdd
        S = out[2 * n :].reshape(2 * n, k)
        S[:n], S[n:] = y[2 * n :].reshape(2 * n, k)[n:], Sa
        return out


def state_dop853(n_state: int) -> type:
    """SciPy's DOP853 whose step-size control reads the first ``n_state`` components only
    (SciPy imported here, on the first run, not with pfaff)."""
    from scipy.integrate import DOP853

    class StateDOP853(DOP853):
        def _estimate_error_norm(self, K: np.ndarray, h: float, scale: np.ndarray) -> float:
            return super()._estimate_error_norm(K[:, :n_state], h, scale[:n_state])

    return StateDOP853


class SensitivityRK(ProjectedRK):
    """``"projection"`` with the sensitivities carried along (a subclass is made per run with
    its :class:`SensitivitySetup` as ``setup``)."""

    name = "projection"
    setup: SensitivitySetup

    def __init__(
        self,
        model: DynamicsModel,
        t0: float,
        q0: np.ndarray,
        qd0: np.ndarray,
        t_end: float,
        options: StepperOptions,
        projector: Projector,
    ) -> None:
        setup = self.setup
        if setup.stepper is not None or t0 != setup.t0:
            raise _RunFailure(
                "sensitivities cannot follow a restart of the integrator (an MRP shadow-set "
                "switch changes the coordinates); use another attitude set"
            )
        setup.stepper = self
        p = np.array(list(model.parameters.values()), dtype=float)
        self.field = AugmentedField(setup, p)
        self.n = n = len(q0)
        S0 = tangent_project(setup.kernel, self._x(t0, q0, qd0), setup.S0)
        y0 = np.concatenate([q0, qd0, S0.ravel()])
        self.solver = state_dop853(2 * n)(
            self.field, t0, y0, t_end, rtol=options.rtol, atol=options.atol, **options.step_sizes()
        )
        self.fun = self.field
        self.projector = projector
        self.stats = {"steps": 0, "rejected": 0, "nfev": 0}
        self._attempt_nfev = self.solver.n_stages
        self._dense = self._y_raw = None
        self._restarts = 0
        setup.records[float(t0)] = S0

    def _x(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        x = self.field.x.copy()
        n = self.n
        x[0], x[1 : 1 + n], x[1 + n : 1 + 2 * n] = t, q, qd
        return x

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        y = self.solver.y
        return y[: self.n], y[self.n : 2 * self.n]

    def step(self) -> None:
        s, n, setup = self.solver, self.n, self.setup
        before = s.nfev
        msg = s.step()
        if s.status == "failed":
            self.fail(f"the integrator failed at t = {s.t:.17g}: {msg}")
        self.stats["steps"] += 1
        self.stats["rejected"] += max((s.nfev - before) // self._attempt_nfev - 1, 0)
        self._dense = None
        t = self.t
        q, qd, _ = self.projector(t, s.y[:n], s.y[n : 2 * n])
        S = s.y[2 * n :].reshape(2 * n, -1)
        S = tangent_project(setup.kernel, self._x(t, q, qd), S)
        self._y_raw = s.y
        s.y = np.concatenate([q, qd, S.ravel()])
        s.f = self.fun(t, s.y)  # restart the FSAL stage from the projected state
        self._restarts += 1
        if setup.report_steps:
            setup.records[float(t)] = S

    def dense(self, ts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """States inside the last step; their sensitivities are recorded for the report."""
        n, k = self.n, self.setup.S0.shape[1]
        out = []
        for ti, (q, rest) in zip(ts, super().dense(ts), strict=True):
            self.setup.records[float(ti)] = rest[n:].reshape(2 * n, k)
            out.append((q, rest[:n]))
        return out

    def step_work(self, power: Power) -> float:
        """The plain run's quadrature on the state part of the augmented stages."""
        n = self.n

        def state_power(t: float, a: np.ndarray, b: np.ndarray) -> float:
            y = np.concatenate((a, b))
            return power(t, y[:n], y[n : 2 * n])

        return super().step_work(state_power)

    def finish(self) -> dict[str, int | float | None]:
        self.stats["nfev"] = self.solver.nfev + self._restarts
        return self.stats


def stepper_for(setup: SensitivitySetup) -> type[SensitivityRK]:
    """The :class:`SensitivityRK` of one run (``simulate(method=...)`` takes a class)."""
    return type("SensitivityRK", (SensitivityRK,), {"setup": setup})
