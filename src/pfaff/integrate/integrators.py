"""ODE-based methods: the acceleration-level equations integrated by SciPy's adaptive Runge–Kutta.

Two separate ideas, each a :class:`pfaff.integrate.stepper.Stepper` (the contract of
:func:`pfaff.simulate`):

- :class:`ProjectedRK` ("projection") integrates q̈ = q̈(q, q̇, t) from the KKT solve and, after
  every accepted step, projects the state back onto f = 0, A q̇ + b = 0 (:mod:`pfaff.numeric.projection`);
  the Runge–Kutta method restarts from the projected state.
- :class:`BaumgarteRK` ("baumgarte") changes the vector field instead: the constraint rows of the
  KKT system ask for A q̈ + Ȧq̇ + ḃ = −2α (A q̇ + b) − β² f, so that the drift obeys a damped
  linear equation rather than growing.

Both fail a run whose constraints can no longer be met (:mod:`pfaff.integrate.reach`).

Small fused models run DOP853 on Python floats (:mod:`pfaff.integrate.fastrk`), others SciPy's solvers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pfaff.core.errors import OptionError
from pfaff.integrate.reach import DriftWatch, unreached
from pfaff.integrate.stepper import Power, Stepper, StepperOptions
from pfaff.integrate.work import checked_sum, dense_work, read_coordinates, state_at
from pfaff.numeric.projection import Projector
from pfaff.numeric.protocol import DynamicsModel, OdeFunction

if TYPE_CHECKING:
    from scipy.integrate import OdeSolver

RK_METHODS = ("DOP853", "RK45", "RK23")  # SciPy's explicit Runge–Kutta solvers, by name


def rk_solver(name: str) -> type[OdeSolver]:
    """SciPy's solver class of that name; ``scipy.integrate`` is imported here, on the first
    run, not with pfaff (it costs a third of pfaff's import time, with ``scipy.optimize``)."""
    import scipy.integrate

    return getattr(scipy.integrate, name)


class _RKStepper(Stepper):
    """One SciPy Runge–Kutta solver driven step by step."""

    def _start(
        self, fun: OdeFunction, t0: float, y0: np.ndarray, t_end: float, opts: StepperOptions
    ) -> None:
        """The solver on ``fun`` from (t0, y0) (the subclasses' ``__init__`` make ``fun``)."""
        name = opts.integrator
        if name not in RK_METHODS:
            raise OptionError(
                f"`integrator` must be one of {', '.join(RK_METHODS)} (explicit Runge–Kutta, "
                f"which can restart from a projected state); got {name!r}"
            )
        kw = opts.step_sizes()
        on_lists = fun.on_lists
        self.solver: OdeSolver
        # fastrk subclasses scipy.integrate.OdeSolver: imported with SciPy's solvers, here
        from pfaff.integrate.fastrk import FLOAT_LIMIT, FloatDOP853
        from pfaff.integrate.inplace import INPLACE_MIN, InPlaceDOP853

        if name == "DOP853" and on_lists is not None and len(y0) <= FLOAT_LIMIT:
            self.solver = FloatDOP853(
                fun, t0, y0, t_end, rtol=opts.rtol, atol=opts.atol, list_fun=on_lists, **kw
            )
        elif name == "DOP853" and fun.into is not None and len(y0) >= INPLACE_MIN:
            self.solver = InPlaceDOP853(
                fun, t0, y0, t_end, rtol=opts.rtol, atol=opts.atol, into=fun.into, **kw
            )
        else:
            cls = rk_solver(name)
            self.solver = cls(fun, t0, y0, t_end, rtol=opts.rtol, atol=opts.atol, **kw)
        self.fun = fun
        self.n = len(y0) // 2
        self.stats = {"steps": 0, "rejected": 0, "nfev": 0}
        self._attempt_nfev = self.solver.n_stages
        self._dense = self._y_raw = None
        self._restarts = 0

    @property
    def t(self) -> float:
        return float(self.solver.t)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        y = self.solver.y
        return y[: self.n], y[self.n :]

    def step(self) -> None:
        before = self.solver.nfev
        msg = self.solver.step()
        used = self.solver.nfev - before
        if self.solver.status == "failed":
            self.fail(f"the integrator failed at t = {self.solver.t:.17g}: {msg}")
        self.stats["steps"] += 1
        self.stats["rejected"] += max(used // self._attempt_nfev - 1, 0)
        self._dense = self._y_raw = None
        self.fun.accepted(self.t, *self.state())

    def dense(self, ts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """States inside the last step (before any projection of its end point)."""
        Y = self._interpolant()(ts)
        return [(Y[: self.n, i], Y[self.n :, i]) for i in range(len(ts))]

    def _interpolant(self):  # type: ignore[no-untyped-def]
        """The solver's dense output of the last step (made once per step)."""
        if self._dense is None:
            s = self.solver
            y, s.y = s.y, self._y_raw if self._y_raw is not None else s.y
            try:
                self._dense = s.dense_output()
            finally:
                s.y = y
        return self._dense

    def endpoints(self) -> tuple[tuple[float, np.ndarray, np.ndarray], ...]:
        """(t, y, ẏ) at both ends of the last step as computed (before any projection of its
        end point): what the step already evaluated, no new right-hand side."""
        s = self.solver
        y1 = self._y_raw if self._y_raw is not None else s.y
        return (float(s.t_old), s.y_old, s.K[0]), (float(s.t), y1, s.K[-1])

    def step_work(self, power: Power) -> float:
        """∫ P dt over the last step by the Runge–Kutta method's own quadrature, h Σ b_i P(t_i, y_i).

        This is what the method would compute for an extra component W' = P(t, y): the same
        order as the step itself (8 for DOP853), from the stage states y_i = y₀ + h Σ a_ij K_j
        the step already has: no new right-hand side, one power evaluation per stage with b_i ≠ 0.
        """
        s = self.solver
        t0, y0, K, A, B, C = float(s.t_old), s.y_old, s.K, s.A, s.B, s.C
        h = float(s.t) - t0
        if hasattr(s, "stage_power"):  # evaluated during the step (pfaff.integrate.inplace)
            if s.stage_power is power and s.stage_values is not None:
                return h * checked_sum(s.stage_values, t0 + h)
            s.stage_power = power  # the next steps evaluate it at their stages
            return h * checked_sum(s.stage_terms(power), t0 + h)
        n, terms = len(y0) // 2, []
        for i, b in enumerate(B):
            if b != 0.0:
                y = y0 + h * (A[i, :i] @ K[:i]) if i else y0
                terms.append(b * power(float(t0 + C[i] * h), y[:n], y[n:]))
        return h * checked_sum(terms, t0 + h)

    def work_until(self, power: Power, b: float) -> float:
        """∫ P dt from the start of the last step to ``b`` inside it, on the dense output.

        Where the power names the few coordinates it reads
        (:func:`pfaff.integrate.work.read_coordinates`: the ring's push reads x alone) and the
        interpolant can give some components (:meth:`pfaff.integrate.inplace._Dense.at`), the
        nodes' states are exact there only, the rest the step's start: a few columns of the
        stages read per node, not 2n values.
        """
        (t0, y0, _), n = self.endpoints()[0], self.n
        dense, idx = self._interpolant(), read_coordinates(power, n)
        if idx is None or not hasattr(dense, "at"):
            return dense_work(self.dense, power, float(t0), b)
        rows, k = np.concatenate([idx, idx + n]), len(idx)

        def states(ts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
            values = [dense.at(float(t), rows) for t in ts]
            return [state_at(y0, idx, v[:k], v[k:]) for v in values]

        return dense_work(states, power, float(t0), b)

    def finish(self) -> dict[str, int | float | None]:
        self.stats["nfev"] = self.solver.nfev + self._restarts
        return self.stats


class ProjectedRK(_RKStepper):
    """Runge–Kutta on the acceleration-level ODE with projection after every accepted step."""

    name = "projection"
    projects_steps = True

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
        fun = model.ode_function(start=(t0, q0, qd0))
        self._start(fun, t0, np.concatenate([q0, qd0]), t_end, options)
        self.projector = projector

    def step(self) -> None:
        super().step()
        t = self.t
        q, qd = self.state()
        q, qd, changed = self.projector(t, q, qd)
        if changed:
            why = unreached(self.projector, t, q, qd)
            if why is not None:
                self.fail(why)
            s = self.solver
            self._y_raw = s.y  # the step's interpolant ends here (see dense)
            s.y = np.concatenate([q, qd])
            s.f = self.fun(t, s.y)  # restart the FSAL stage from the projected state
            self._restarts += 1


class BaumgarteRK(_RKStepper):
    """Runge–Kutta on the Baumgarte-stabilized acceleration-level ODE (no projection)."""

    name = "baumgarte"
    reports_drift = True

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
        fun = model.ode_function(options.alpha, options.beta, start=(t0, q0, qd0))
        self._start(fun, t0, np.concatenate([q0, qd0]), t_end, options)
        self.watch = DriftWatch(projector)

    def step(self) -> None:
        """One step; the run fails where the drift it lets grow cannot be projected away
        (:mod:`pfaff.integrate.reach`)."""
        super().step()
        why = self.watch(self.t, *self.state())
        if why is not None:
            self.fail(why)
