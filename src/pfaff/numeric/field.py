"""y' = [q̇, q̈] of a general model for the integrators: :class:`AccelerationField`."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from pfaff.core.errors import StateError
from pfaff.numeric.kkt import FLOOR, RESCALE_BELOW
from pfaff.numeric.protocol import OdeFunction
from pfaff.numeric.redundant import independent_rows

if TYPE_CHECKING:
    from pfaff.numeric.model import NumericModel


def not_real(t: float) -> str:
    return (
        f"the equations are not real at t = {t:.17g}: a fractional power of a negative value "
        "(write it with sqrt, cbrt or Abs where the model allows)"
    )


class AccelerationField(OdeFunction):
    """y' = [q̇, q̈] of a :class:`NumericModel` for the integrators, with the rank-loss floor.

    Small fused systems get the generated right-hand side (a few microseconds per call) and
    :attr:`on_lists`, the same function on lists of floats (:mod:`pfaff.integrate.fastrk`).
    A non-finite q̈ raises :class:`StateError` naming the time.

    The floor's reference row sizes (:mod:`pfaff.numeric.kkt`) are kept current: a row that
    starts (nearly) collapsed, a linkage released from a flat configuration, has no size of its
    own yet; while any row is below ``RESCALE_BELOW`` of the largest, the sizes at each accepted
    step raise the references (a running maximum) and the right-hand side is rebuilt.
    """

    def __init__(
        self,
        model: NumericModel,
        alpha: float,
        beta: float,
        scales: np.ndarray | None,
        before: Callable[[float, np.ndarray, np.ndarray], None] | None = None,
    ) -> None:
        self.model, self.alpha, self.beta, self.before = model, alpha, beta, before
        self.scales = None if scales is None else np.asarray(scales, dtype=float)
        self.active = self.scales is not None and self._small_rows()
        self._rhs: list = []  # [rhs(t, y: list) -> list] of a fused model, replaced on rescaling
        if model._fused is not None:
            self._rhs.append(model._fused_rhs(alpha, beta, self.scales))
            self.on_lists = _checked_lists(self._rhs, before, model.n)

    def _small_rows(self) -> bool:
        ref = self.scales
        return ref is not None and bool((ref < RESCALE_BELOW * ref.max()).any())

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        if self.on_lists is not None:
            return np.array(self.on_lists(t, y.tolist()))
        n = self.model.n
        if self.before is not None:
            self.before(t, y[:n], y[n:])
        out = np.empty(2 * n)
        out[:n] = y[n:]
        m = self.model
        out[n:] = m._solve(t, y[:n], y[n:], self.alpha, self.beta, floor=FLOOR, scales=self.scales)[
            0
        ]
        if not math.isfinite(out.sum()):
            raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
        return out

    def accepted(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """Raise the reference row sizes to those at (t, q, q̇) while some row is small; where
        the run's constraints are redundant, choose its independent rows again (pivoted QR at
        the accepted state: the set that is independent may change along the motion)."""
        run = self.model._run_state
        if run["rows"] is not None:
            n = self.model.n
            rows = independent_rows(self.model._kkt(t, q, qd)[0][n:, :n])
            if rows is not None:
                run["rows"] = rows
        if not self.active or self.scales is None:
            return
        now = self.model._row_scales(t, q, qd)
        if now is None:
            return
        new = np.maximum(self.scales, now)
        if (new > self.scales).any():
            self.scales = new
            if self._rhs:
                self._rhs[0] = self.model._fused_rhs(self.alpha, self.beta, new)
        self.active = self._small_rows()


def _checked_lists(
    rhs: list, before: Callable | None = None, n: int = 0
) -> Callable[[float, list], list]:
    """``rhs[0]`` with its result checked: finite and real (a closure: the hot path of small
    systems); ``before(t, q, q̇)`` first, when given (a run's inputs)."""
    isfinite = math.isfinite
    array = np.array

    def on_lists(t: float, yl: list) -> list:
        if before is not None:
            before(t, array(yl[:n]), array(yl[n:]))
        out = rhs[0](t, yl)
        try:
            finite = isfinite(sum(out))
        except TypeError:  # a complex number: a fractional power of a negative value
            raise StateError(not_real(t)) from None
        if not finite:
            raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
        return out

    return on_lists
