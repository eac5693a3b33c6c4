"""Integrate stage: DOP853 on Python floats, for systems of a handful of coordinates.

SciPy's ``DOP853`` spends about 8 µs per stage in NumPy calls on arrays of length four: more than
pfaff's fused right-hand side of a pendulum. For small systems this module runs the same method
(Dormand–Prince 8(5,3), the tableau read from ``scipy.integrate.DOP853``, the same error norm and
step-size controller) with straight-line generated code on lists of floats. The class mimics the
part of SciPy's ``OdeSolver`` the steppers of :mod:`pfaff.integrators` use (``t``, ``y``, ``f``,
``nfev``, ``status``, ``n_stages``, ``step()``, ``dense_output()``), so that everything else —
projection, restarts, dense output at ``t_eval`` — is shared with the SciPy path.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import numpy as np
from scipy.integrate import DOP853

FLOAT_LIMIT = 24  # state sizes (2n) up to which the float code is used
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0  # the usual step-size controller constants
_EXPONENT = -1.0 / (DOP853.error_estimator_order + 1)


def _combo(coefs: np.ndarray, i: int) -> str:
    terms = [f"{float(c)!r}*k{j}_{i}" for j, c in enumerate(coefs) if c != 0.0]
    return " + ".join(terms) if terms else "0.0"


@lru_cache(maxsize=16)
def _step_function(size: int) -> Callable:
    """``step(fun, t, y, k0, h, rtol, atol) -> (y_new, f_new, err5², err3², stages)``.

    Every component of every stage is a local variable (``k3_1``): no list indexing in the sums.
    """
    A, B, C, E3, E5 = DOP853.A, DOP853.B, DOP853.C, DOP853.E3, DOP853.E5
    S = DOP853.n_stages

    def unpack(name: str) -> str:
        return f"    {', '.join(f'{name}_{i}' for i in range(size))}, = {name}"

    lines = ["def step(fun, t, y, k0, h, rtol, atol):", unpack("y"), unpack("k0")]
    for s in range(1, S):
        ys = [f"y_{i} + h*({_combo(A[s, :s], i)})" for i in range(size)]
        lines.append(f"    k{s} = fun(t + {float(C[s])!r}*h, [{', '.join(ys)}])")
        lines.append(unpack(f"k{s}"))
    yn = [f"y_{i} + h*({_combo(B, i)})" for i in range(size)]
    lines.append(f"    yn = [{', '.join(yn)}]")
    lines.append(unpack("yn"))
    lines.append(f"    k{S} = fun(t + h, yn)")
    lines.append(unpack(f"k{S}"))
    lines.append("    e5 = e3 = 0.0")
    for i in range(size):
        lines.append(f"    sc = atol[{i}] + max(abs(y_{i}), abs(yn_{i}))*rtol")
        lines.append(f"    a = ({_combo(E5, i)})/sc")
        lines.append(f"    b = ({_combo(E3, i)})/sc")
        lines.append("    e5 += a*a")
        lines.append("    e3 += b*b")
    lines.append(f"    return yn, k{S}, e5, e3, [{', '.join(f'k{s}' for s in range(S + 1))}]")
    namespace: dict = {}
    exec(compile("\n".join(lines) + "\n", "<pfaff.fastrk>", "exec"), namespace)  # our own code
    return namespace["step"]


class FloatDOP853:
    """DOP853 on lists of floats, with the interface of SciPy's solver object.

    Parameters
    ----------
    fun : callable
        ``fun(t, y: list) -> list`` (the fast path) of the state's derivative.
    array_fun : callable
        The same on arrays (for the dense-output stages and restarts).
    t0, y0, t_bound, rtol, atol, max_step, first_step
        As for ``scipy.integrate.DOP853``; its constructor validates them and picks the first step.

    Examples
    --------
    >>> import math
    >>> s = FloatDOP853(lambda t, y: [y[1], -y[0]], None, 0.0, [0.0, 1.0], math.pi, 1e-10, 1e-12)
    >>> while s.status == "running":
    ...     _ = s.step()
    >>> [round(float(v), 8) + 0.0 for v in s.y]
    [0.0, -1.0]
    """

    n_stages = DOP853.n_stages

    def __init__(
        self,
        fun: Callable,
        array_fun: Callable | None,
        t0: float,
        y0,
        t_bound: float,
        rtol: float,
        atol: float,
        **kw,
    ) -> None:
        self.lfun = fun
        self.array_fun = array_fun or (lambda t, y: np.array(fun(t, list(y))))
        ref = DOP853(
            self.array_fun, t0, np.asarray(y0, dtype=float), t_bound, rtol=rtol, atol=atol, **kw
        )
        # Python floats throughout: one NumPy scalar would turn every stage sum into NumPy calls
        self.t, self._y, self._f = float(ref.t), ref.y.tolist(), ref.f.tolist()
        self.t_bound, self.direction = float(ref.t_bound), float(ref.direction)
        self.rtol, self.max_step, self.h_abs = (
            float(ref.rtol),
            float(ref.max_step),
            float(ref.h_abs),
        )
        self.atol = np.broadcast_to(ref.atol, (len(self._y),)).astype(float).tolist()
        self.nfev = ref.nfev
        self.status = "running" if self.t != t_bound else "finished"
        self._step = _step_function(len(self._y))
        self._last: tuple | None = None  # (t_old, h, y_old, stages) of the last accepted step

    # the SciPy solver attributes, as arrays
    @property
    def y(self) -> np.ndarray:
        return np.array(self._y)

    @y.setter
    def y(self, value) -> None:
        self._y = np.asarray(value, dtype=float).tolist()

    @property
    def f(self) -> np.ndarray:
        return np.array(self._f)

    @f.setter
    def f(self, value) -> None:
        self._f = np.asarray(value, dtype=float).tolist()

    def step(self) -> str | None:
        """One accepted step (rejected attempts included); a message on failure."""
        t, y, d = self.t, self._y, self.direction
        min_step = 10.0 * abs(math.nextafter(t, d * math.inf) - t)
        h_abs = min(max(self.h_abs, min_step), self.max_step)
        rejected = False
        size = len(y)
        while True:
            if h_abs < min_step:
                self.status = "failed"
                return "Required step size is less than spacing between numbers."
            t_new = t + h_abs * d
            if d * (t_new - self.t_bound) > 0:
                t_new = self.t_bound
            h = t_new - t
            h_abs = abs(h)
            yn, fn, e5, e3, stages = self._step(self.lfun, t, y, self._f, h, self.rtol, self.atol)
            self.nfev += self.n_stages
            err = 0.0 if e5 == 0.0 and e3 == 0.0 else h_abs * e5 / (size * (e5 + 0.01 * e3)) ** 0.5
            if err < 1.0:
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**_EXPONENT)
                self.h_abs = float(h_abs * (min(1.0, factor) if rejected else factor))
                break
            h_abs *= max(MIN_FACTOR, SAFETY * err**_EXPONENT)
            rejected = True
        self._last = (t, h, y, yn, stages)
        self.t, self._y, self._f = t_new, yn, fn
        if d * (self.t - self.t_bound) >= 0:
            self.status = "finished"
        return None

    def dense_output(self) -> Callable[[np.ndarray], np.ndarray]:
        """The 7th-degree DOP853 interpolant over the last step (three more stages).

        It interpolates the step as computed, before any projection of its end point.
        """
        assert self._last is not None
        t_old, h, y_old, y_new, stages = self._last
        K = np.empty((DOP853.A_EXTRA.shape[1], len(y_old)))
        K[: self.n_stages + 1] = stages
        y0 = np.array(y_old)
        for s, (a, c) in enumerate(
            zip(DOP853.A_EXTRA, DOP853.C_EXTRA, strict=True), self.n_stages + 1
        ):
            K[s] = self.array_fun(t_old + c * h, y0 + h * (a[:s] @ K[:s]))
            self.nfev += 1
        dy = np.array(y_new) - y0
        F = np.empty((DOP853.D.shape[0] + 3, len(y0)))
        F[0] = dy
        F[1] = h * K[0] - dy
        F[2] = 2 * dy - h * (K[self.n_stages] + K[0])
        F[3:] = h * (DOP853.D @ K)

        def interpolate(ts: np.ndarray) -> np.ndarray:
            x = (np.asarray(ts, dtype=float) - t_old) / h
            out = np.zeros((len(y0), x.size))
            for i, row in enumerate(F[::-1]):
                out += row[:, None]
                out *= x if i % 2 == 0 else 1.0 - x
            return out + y0[:, None]

        return interpolate
