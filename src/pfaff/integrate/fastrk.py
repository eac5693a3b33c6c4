"""Integrate stage: DOP853 on Python floats, for systems of a handful of coordinates.

SciPy's ``DOP853`` spends about 8 µs per stage in NumPy calls on arrays of length four: more than
pfaff's fused right-hand side of a pendulum. For small systems this module runs the same method
(Dormand–Prince 8(5,3), the tableau read from ``scipy.integrate.DOP853``, the same error norm and
step-size controller) with straight-line generated code on lists of floats. It is a
:class:`scipy.integrate.OdeSolver` (SciPy's stepping contract and dense output), so that everything
else (projection, restarts, dense output at ``t_eval``, the work integral) is shared with the SciPy
path.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import numpy as np
from scipy.integrate import DOP853, DenseOutput, OdeSolver

FLOAT_LIMIT = 24  # state sizes (2n) up to which the float code is used
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0  # the usual step-size controller constants
_EXPONENT = -1.0 / (DOP853.error_estimator_order + 1)
EPS = np.finfo(float).eps


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


class FloatDOP853(OdeSolver):
    """DOP853 on lists of floats: a :class:`scipy.integrate.OdeSolver` for small systems.

    The same method as ``scipy.integrate.DOP853`` (its tableau, error norm and step-size
    controller), with SciPy's stepping contract (``step()``, ``t_old``, ``status``, ``nfev``,
    ``dense_output()`` returning a :class:`scipy.integrate.DenseOutput`), so it can be driven like
    any SciPy solver. Justified by ``benchmarks/simulate.py``: SciPy's DOP853 spends about 8 µs
    per stage in NumPy calls on arrays of length four; on floats the Cartesian pendulum's 2000 s
    check runs at 1.5× a one-angle DOP853 (2.8× before this path).

    Parameters
    ----------
    fun : callable
        ``fun(t, y: ndarray) -> ndarray``, shape (n,): the derivative (restarts, dense output).
    t0 : float
    y0 : array_like, shape (n,)
    t_bound : float
    max_step, rtol, atol, first_step
        As for ``scipy.integrate.DOP853``.
    list_fun : callable, optional
        ``list_fun(t, y: list) -> list``: the same derivative on lists of floats (the fast path);
        by default ``fun`` wrapped.

    Examples
    --------
    >>> import math
    >>> s = FloatDOP853(lambda t, y: np.array([y[1], -y[0]]), 0.0, [0.0, 1.0], math.pi,
    ...                 rtol=1e-10, atol=1e-12)
    >>> while s.status == "running":
    ...     _ = s.step()
    >>> [round(float(v), 8) + 0.0 for v in s.y]
    [0.0, -1.0]
    >>> tm = (s.t_old + s.t) / 2  # the dense output inside the last step: y = sin t
    >>> bool(abs(s.dense_output()(tm)[0] - math.sin(tm)) < 1e-9)
    True
    """

    n_stages = DOP853.n_stages
    order, error_estimator_order = DOP853.order, DOP853.error_estimator_order
    A, B, C = DOP853.A, DOP853.B, DOP853.C

    def __init__(
        self,
        fun: Callable,
        t0: float,
        y0,
        t_bound: float,
        max_step: float = np.inf,
        rtol: float = 1e-3,
        atol: float = 1e-6,
        first_step: float | None = None,
        *,
        list_fun: Callable | None = None,
        vectorized: bool = False,
        **extraneous: object,
    ) -> None:
        super().__init__(fun, t0, y0, t_bound, vectorized=vectorized)
        self.lfun = list_fun or (lambda t, y: self.fun_single(t, np.array(y)).tolist())
        self.t, self.t_bound = float(t0), float(t_bound)
        self.direction = float(self.direction)
        self.max_step = _positive(max_step, "max_step")
        rtol = max(float(rtol), 100 * EPS)  # SciPy's floor for rtol
        atol_arr = np.broadcast_to(np.asarray(atol, dtype=float), (self.n,))
        if not (math.isfinite(rtol) and np.all(atol_arr >= 0)):
            raise ValueError("rtol must be finite and atol non-negative")
        self.rtol, self.atol = rtol, atol_arr.tolist()
        self._f = self.fun(self.t, np.array(self._y)).tolist()
        if first_step is None:
            self.h_abs = self._initial_step()
        else:
            self.h_abs = _positive(first_step, "first_step")
            if self.h_abs > abs(self.t_bound - self.t):
                raise ValueError("first_step exceeds bounds")
        self._step = _step_function(self.n)
        self._y_old: list[float] | None = None
        self._stages: list | None = None  # K_0 … K_S of the last accepted step

    # the SciPy solver attributes, as arrays (Python floats inside)
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

    @property
    def y_old(self) -> np.ndarray | None:
        """The state at the start of the last step."""
        return None if self._y_old is None else np.array(self._y_old)

    @property
    def K(self) -> np.ndarray:
        """The stages K_0 … K_S of the last step, shape (n_stages + 1, n), as in SciPy's RK."""
        return np.array(self._stages)

    def _initial_step(self) -> float:
        """The usual starting-step estimate (Hairer, Nørsett & Wanner, Solving ODE I, II.4) from
        the sizes of y, f and a trial Euler step's f, with the error estimator's order (7), as
        SciPy's DOP853 chooses it."""
        y0, f0 = np.array(self._y), np.array(self._f)
        interval = abs(self.t_bound - self.t)
        if interval == 0.0:
            return 0.0
        scale = np.maximum(np.array(self.atol) + np.abs(y0) * self.rtol, np.finfo(float).tiny)
        with np.errstate(all="ignore"):  # huge ratios (atol = 1e-300) fall back to a tiny step
            d0, d1 = _rms(y0 / scale), _rms(f0 / scale)
        if not (math.isfinite(d0) and math.isfinite(d1)):
            return min(1e-6, interval, self.max_step)
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, interval)
        y1 = y0 + h0 * self.direction * f0
        f1 = self.fun(self.t + h0 * self.direction, y1)
        with np.errstate(all="ignore"):
            d2 = _rms((f1 - f0) / scale) / h0
        if not math.isfinite(d2):
            return min(h0, interval, self.max_step)
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1 / (self.error_estimator_order + 1))
        return min(100 * h0, h1, interval, self.max_step)

    def _step_impl(self) -> tuple[bool, str | None]:
        """One accepted step (rejected attempts included), as SciPy's ``OdeSolver.step`` wants."""
        t, y, d = self.t, self._y, self.direction
        min_step = 10.0 * abs(math.nextafter(t, d * math.inf) - t)
        h_abs = min(max(self.h_abs, min_step), self.max_step)
        rejected = False
        size = len(y)
        while True:
            if h_abs < min_step:
                return False, "Required step size is less than spacing between numbers."
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
        self._y_old, self._stages = y, stages
        self.t, self._y, self._f = t_new, yn, fn
        return True, None

    def _dense_output_impl(self) -> DenseOutput:
        """The 7th-degree DOP853 interpolant over the last step (three more stages).

        It interpolates the step as computed, before any projection of its end point.
        """
        t_old, y0 = float(self.t_old), np.array(self._y_old)
        h = self.t - t_old
        K = np.empty((DOP853.A_EXTRA.shape[1], len(y0)))
        K[: self.n_stages + 1] = self._stages
        for s, (a, c) in enumerate(
            zip(DOP853.A_EXTRA, DOP853.C_EXTRA, strict=True), self.n_stages + 1
        ):
            K[s] = self.fun(t_old + c * h, y0 + h * (a[:s] @ K[:s]))
        dy = np.array(self._y) - y0
        F = np.empty((DOP853.D.shape[0] + 3, len(y0)))
        F[0] = dy
        F[1] = h * K[0] - dy
        F[2] = 2 * dy - h * (K[self.n_stages] + K[0])
        F[3:] = h * (DOP853.D @ K)
        return _Dop853Dense(t_old, self.t, y0, F)


class _Dop853Dense(DenseOutput):
    """DOP853's dense output: the polynomial of F (as SciPy forms it) in x = (t − t_old)/h."""

    def __init__(self, t_old: float, t: float, y_old: np.ndarray, F: np.ndarray) -> None:
        super().__init__(t_old, t)
        self.h, self.y_old, self.F = t - t_old, y_old, F

    def _call_impl(self, t: np.ndarray) -> np.ndarray:
        x = (np.atleast_1d(np.asarray(t, dtype=float)) - self.t_old) / self.h
        out = np.zeros((len(self.y_old), x.size))
        for i, row in enumerate(self.F[::-1]):
            out += row[:, None]
            out *= x if i % 2 == 0 else 1.0 - x
        out += self.y_old[:, None]
        return out[:, 0] if np.ndim(t) == 0 else out


def _rms(x: np.ndarray) -> float:
    return float(np.linalg.norm(x) / np.sqrt(x.size)) if x.size else 0.0


def _positive(value: float, name: str) -> float:
    v = float(value)
    if not v > 0:
        raise ValueError(f"`{name}` must be positive.")
    return v
