"""Integrate stage: DOP853 with its stage sums in place, for the long states of family models.

SciPy's ``DOP853`` forms every stage state as ``y + np.dot(K[:s].T, a) * h``: two fresh 2N-long
arrays per stage (13 per step, more for the error estimate), each written once and freed. On the
pushed ring at N = 2^20 those sums were 57 % of a run, mostly the page faults of the fresh arrays
and the copies, not the arithmetic. :class:`InPlaceDOP853` is the same method (SciPy's tableau,
error norm and step-size controller, read from ``scipy.integrate.DOP853``) whose step writes every
stage state into one preallocated buffer (``np.dot(h a, K[:s], out=stage)``, one pass of BLAS over
the stages, then ``stage += y``) and whose right-hand side writes q̈ straight into its row of ``K``
(``OdeFunction.into``). A step allocates one array, its result y (the driver and the projection may
keep it). It is a :class:`scipy.integrate.OdeSolver` like SciPy's own (it subclasses ``DOP853``):
dense output, restarts from a projected state and the work integral are SciPy's and pfaff's
usual ones. The results agree with SciPy's to rounding (the sums are ordered differently), with
the same steps (``tests/integrate/test_inplace.py``); ``benchmarks/ring_scale.py --simulate``
measures both.

From 2n = :data:`JIT_MIN` on, the sums are compiled loops (:mod:`pfaff.integrate.inplacejit`,
numba, when it loads): each stage state y + h Σ a_sj K_j in one pass (BLAS's product and then
``+= y`` were two), the solution y_new with both error estimates' sums of squares in one pass over
K (48 ms → 25 ms at 2n = 2^21), each extra stage of the dense output and each dense-output value in
one pass instead of six (48 ms → 35 ms). Every compiled sum runs over spans of :data:`SPAN`
components handed to the kernel threads (:func:`pfaff.numeric.streams.in_spans`: on two threads
from 2^20 components, the thread policy of :mod:`pfaff.numeric.streams`); a component is computed
the same way on any thread, and the error norm's sums of squares are added span by span in order,
so that a run's results do not depend on the thread count.

The work integral of a step, h Σ b_i P(t_i, y_i), needs the stage states again; once the driver
has asked for it (``stage_power``), the step evaluates P at each stage with b_i ≠ 0 while that
stage's state is in the buffer, instead of forming the states a second time afterwards.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.integrate import DOP853, DenseOutput

from pfaff.integrate import inplacejit
from pfaff.numeric import streams

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0  # SciPy's step-size controller constants
INPLACE_MIN = 4096  # state sizes (2n) from which the in-place path is taken
JIT_MIN = 1 << 17  # ... and from which its sums are compiled loops (inplacejit; numba loaded)
BLOCK = 1 << 13  # components per block of the error norm (K's block stays in L2)
SPAN = streams.SPAN  # components per task of the compiled sums on the kernel threads
INTERPOLATOR_POWER = 3 + DOP853.D.shape[0]  # the degree of DOP853's interpolant
# The row of K each stage's derivative goes to. K_1 is read by stage 2 alone and K_2 by stages 3
# and 4, and neither by the solution, the error estimate or the interpolant (their coefficients
# there are zero): K_3 takes K_1's row and K_5 K_2's. 11 rows instead of 13: 512 MB less at 2^24.
ROW = (0, 1, 2, 1, 3, 2, 4, 5, 6, 7, 8, 9, 10)
ROWS = max(ROW) + 1


def _rows(coefs: np.ndarray) -> np.ndarray:
    """Coefficients over the stages 0, 1, ... as coefficients over the rows of K."""
    out = np.zeros(ROWS)
    for j, c in enumerate(coefs):
        out[ROW[j]] += c
    return out


def _reads(s: int) -> int:
    """How many rows of K the sum of stage s reads (the rows of the stages before it)."""
    return 1 + max(ROW[:s])


Into = Callable[[float, np.ndarray, np.ndarray], None]  # writes y'(t, y) into its third argument


class InPlaceDOP853(DOP853):
    """``scipy.integrate.DOP853`` with its stage sums and error estimate on preallocated buffers.

    Parameters
    ----------
    fun : callable
        ``fun(t, y) -> ndarray`` shape (2n,): the derivative (start, dense output, restarts).
    t0, y0, t_bound, max_step, rtol, atol, first_step
        As for ``scipy.integrate.DOP853``.
    into : callable
        ``into(t, y, out)``: the same derivative written into ``out`` (shape (2n,)).

    Examples
    --------
    >>> def into(t, y, out):
    ...     out[0], out[1] = y[1], -y[0]
    >>> s = InPlaceDOP853(lambda t, y: np.array([y[1], -y[0]]), 0.0, [0.0, 1.0], np.pi,
    ...                   rtol=1e-10, atol=1e-12, into=into)
    >>> while s.status == "running":
    ...     _ = s.step()
    >>> [round(float(v), 8) + 0.0 for v in s.y]
    [0.0, -1.0]
    """

    def __init__(self, fun: Callable, t0: float, y0, t_bound: float, *, into: Into, **kw) -> None:
        super().__init__(fun, t0, y0, t_bound, **kw)
        self._into = into
        n = self.n
        self.K = np.zeros((ROWS, n))  # (see ROW; zeros: a row not yet written is finite)
        self._A = np.array([_rows(self.A[s, :s]) for s in range(self.n_stages)])
        self._B, self._E5, self._E3 = _rows(self.B), _rows(self.E5), _rows(self.E3)
        self._stage = np.empty(n)  # the state of the stage being evaluated
        self._scale, self._err = np.empty(BLOCK), np.empty(2 * BLOCK)  # (the error norm's)
        self._E53 = np.array([self._E5, self._E3])  # both error estimates' rows, (2, ROWS)
        # the rows the solution and the error estimates read: up to their last nonzero
        # coefficient (K's last row, f(t + h, y_new), is not one of them: one row less read)
        self._used = 1 + int(np.flatnonzero(np.abs(self._B) + np.abs(self._E53).sum(0))[-1])
        self.steps = 0  # accepted steps: an interpolant is valid until the next one
        self._extra: np.ndarray | None = None  # the dense output's three extra stages
        self.K_extended = None  # (SciPy's 16 rows: replaced by K and the dense output's own)
        self.stage_power: Callable | None = None  # P(t, q, q̇) evaluated at the stages
        self.stage_values: list[float] | None = None  # b_i P_i of the last accepted step
        self._jit = inplacejit.kernels() if n >= JIT_MIN else None  # (combine, solution+error)
        if self._jit is not None:
            self._norms = (0.0, 0.0)  # the last attempt's sums of squares (solution_and_error)
            self._E53u = np.ascontiguousarray(self._E53[:, : self._used])
            self._atol = np.atleast_1d(np.asarray(self.atol, dtype=float))
            self._span = SPAN  # (read at build time: tests change it)
            self._squares_of = np.zeros((2, -(-n // self._span)))  # per span: Σ (ε₅/s)², Σ (ε₃/s)²
            self._none, self._one = np.zeros(0), np.array([1.0, 0.0, 0.0])

    def _rhs(self, t: float, y: np.ndarray, out: np.ndarray) -> None:
        self._into(t, y, out)
        self.nfev += 1

    def _rk_step(self, t: float, y: np.ndarray, h: float, y_new: np.ndarray) -> list[float]:
        """One attempt: K[1:] and y_new written in place (K[0] holds f(t, y) already); the
        terms b_i P(t_i, y_i) of the work integral when ``stage_power`` is set."""
        K, B, C, stage = self.K, self.B, self.C, self._stage
        power, n, terms = self.stage_power, self.n // 2, []
        if power is not None and B[0] != 0.0:
            terms.append(B[0] * power(t, y[:n], y[n:]))
        for s in range(1, self.n_stages):
            self._stage_state(s, y, h)
            ts = t + C[s] * h
            if power is not None and B[s] != 0.0:
                terms.append(B[s] * power(ts, stage[:n], stage[n:]))
            self._rhs(ts, stage, K[ROW[s]])
        u = self._used
        if self._jit is not None:  # y_new and the error norm's sums in one pass
            self._solution_and_error(h * self._B[:u], y, y_new)
        else:
            np.dot(h * self._B[:u], K[:u], out=y_new)
            y_new += y
        self._rhs(t + h, y_new, K[ROW[-1]])
        return terms

    def _stage_state(self, s: int, y: np.ndarray, h: float) -> None:
        """The state of stage s, y + h Σ_j a_sj K_j, into the stage buffer: one compiled pass
        over spans on the kernel threads, or BLAS's product and then ``+= y``."""
        u, stage = _reads(s), self._stage
        if self._jit is not None:
            self._spans(h * self._A[s, :u], self.K, self._none, self.K, self._one, y, y, y, stage)
            return
        np.dot(h * self._A[s, :u], self.K[:u], out=stage)
        stage += y

    def _spans(self, *args: object) -> None:
        """:func:`pfaff.integrate.inplacejit.combine` over the spans of its output (the last
        argument), on the kernel threads."""
        fn = self._jit[0]  # type: ignore[index]
        streams.in_spans(self.n, self._span, lambda lo, hi: fn(*args, lo, hi))

    def _solution_and_error(self, b: np.ndarray, y: np.ndarray, y_new: np.ndarray) -> None:
        """y_new = y + Σ b_i K_i and the error norm's sums of squares (``_norms``), span by span
        on the kernel threads; the spans' sums added in their order (any thread count: the
        same sums)."""
        fn, parts, span = self._jit[1], self._squares_of, self._span  # type: ignore[index]
        K, E, atol, rtol = self.K, self._E53u, self._atol, self.rtol

        def part(lo: int, hi: int) -> None:
            parts[:, lo // span] = fn(b, E, K, y, y_new, atol, rtol, lo, hi)

        streams.in_spans(self.n, span, part)
        self._norms = (float(parts[0].sum()), float(parts[1].sum()))

    def stage_terms(self, power: Callable) -> list[float]:
        """b_i P(t_i, y_i) of the last step, its stage states formed again from K (the rows
        of the stages with b_i ≠ 0 and of those their states sum are all still there)."""
        t0, y0, h, n = float(self.t_old), self.y_old, self.h_previous, self.n // 2
        stage, terms = self._stage, []
        for i, b in enumerate(self.B):
            if b == 0.0:
                continue
            if i:
                self._stage_state(i, y0, h)
            y = stage if i else y0
            terms.append(b * power(float(t0 + self.C[i] * h), y[:n], y[n:]))
        return terms

    def _error_norm(self, y: np.ndarray, y_new: np.ndarray, h: float) -> float:
        """SciPy's DOP853 error norm from the sums of squares of both scaled estimates (those
        :meth:`_rk_step` summed with y_new when compiled, else :meth:`_squares`)."""
        n5, n3 = self._norms if self._jit is not None else self._squares(y, y_new)
        if n5 == 0 and n3 == 0:
            return 0.0
        return abs(h) * n5 / np.sqrt((n5 + 0.01 * n3) * self.n)

    def _squares(self, y: np.ndarray, y_new: np.ndarray) -> tuple[float, float]:
        """Σ (ε₅/s)² and Σ (ε₃/s)² over blocks of :data:`BLOCK` components (the scale and the
        two estimates of a block in cache-sized buffers: no array of the state's length). Both
        estimates come from one product with the block of K, which is read once."""
        K, sc, e = self.K, self._scale, self._err
        atol, rtol, n5, n3 = self.atol, self.rtol, 0.0, 0.0
        for i in range(0, self.n, BLOCK):
            j = min(i + BLOCK, self.n)
            s_, e_ = sc[: j - i], e[: 2 * (j - i)].reshape(2, j - i)  # (C-contiguous)
            np.abs(y[i:j], out=s_)
            np.abs(y_new[i:j], out=e_[0])
            np.maximum(s_, e_[0], out=s_)
            s_ *= rtol
            s_ += atol[i:j] if np.ndim(atol) else atol
            np.dot(self._E53[:, : self._used], K[: self._used, i:j], out=e_)
            e_ /= s_
            n5 += float(np.dot(e_[0], e_[0]))
            n3 += float(np.dot(e_[1], e_[1]))
        return n5, n3

    def _dense_output_impl(self) -> DenseOutput:
        """SciPy's DOP853 interpolant of the last step, as one weighted sum of the stages per
        requested time (:class:`_Dense`): SciPy's forms seven state-long coefficient arrays
        first (1.8 GB at 2^24 particles). Its three extra stages go to an array of their own,
        dropped when the next step starts (resident only while the step has a dense output)."""
        K, h, stage, S = self.K, self.h_previous, self._stage, self.n_stages + 1
        extra = self._extra = np.empty((len(self.C_EXTRA), self.n))
        for i, (a, c) in enumerate(zip(self.A_EXTRA, self.C_EXTRA, strict=True)):
            if self._jit is not None:  # one pass: y₀ + h Σ a K + h Σ a' (extra stages before)
                y0 = self.y_old
                self._spans(
                    h * _rows(a[:S]), K, h * a[S : S + i], extra, self._one, y0, y0, y0, stage
                )
                self._rhs(self.t_old + c * h, stage, extra[i])
                continue
            np.dot(h * _rows(a[:S]), K, out=stage)
            if i:  # the extra stages before this one (its own row, not yet written, as scratch)
                np.dot(h * a[S : S + i], extra[:i], out=extra[i])
                stage += extra[i]
            stage += self.y_old
            self._rhs(self.t_old + c * h, stage, extra[i])
        return _Dense(self, h)

    def _step_impl(self) -> tuple[bool, str | None]:
        """SciPy's ``RungeKutta._step_impl`` (the same controller), stages in place."""
        t, y = self.t, self.y
        min_step = 10 * np.abs(np.nextafter(t, self.direction * np.inf) - t)
        h_abs = min(max(self.h_abs, min_step), self.max_step)
        self.K[0] = self.f  # (the stages write K[1:] only: K[0] survives a rejection)
        self._extra = None  # (the last step's extra stages: freed)
        y_new = np.empty(self.n)
        accepted = rejected = False
        while not accepted:
            if h_abs < min_step:
                return False, self.TOO_SMALL_STEP
            t_new = t + h_abs * self.direction
            if self.direction * (t_new - self.t_bound) > 0:
                t_new = self.t_bound
            h = t_new - t
            h_abs = abs(h)
            terms = self._rk_step(t, y, h, y_new)
            error = self._error_norm(y, y_new, h)
            if error < 1:
                factor = (
                    MAX_FACTOR
                    if error == 0
                    else min(MAX_FACTOR, SAFETY * error**self.error_exponent)
                )
                h_abs *= min(1, factor) if rejected else factor
                accepted = True
            else:
                h_abs *= max(MIN_FACTOR, SAFETY * error**self.error_exponent)
                rejected = True
        self.h_previous, self.y_old = h, y
        self.t, self.y, self.h_abs = t_new, y_new, h_abs
        self.f = self.K[-1]  # (a view: the next step copies it into K[0] before any stage)
        self.stage_values = terms if self.stage_power is not None else None
        self.steps += 1
        return True, None


class _Dense(DenseOutput):
    """The DOP853 interpolant of :class:`InPlaceDOP853`'s last step, valid until its next.

    SciPy's is y = y₀ + Σ_j c_j(x) F_j, x = (t − t₀)/h, with F = [Δ, h f₀ − Δ, 2Δ − h (f + f₀),
    h D K] (Δ = y − y₀, f₀ = K₀). Gathered per time: y = (1 − a) y₀ + a y − c₂ h f + w K, with
    a = c₀ − c₁ + 2c₂ and w = h (c₃…c₆) D + h (c₁ − c₂) e₀: one product with the 16 stages.
    """

    def __init__(self, solver: InPlaceDOP853, h: float) -> None:
        super().__init__(solver.t_old, solver.t)
        self.solver, self.h, self.step = solver, h, solver.steps
        self.y_old, self.y, self.f = solver.y_old, solver.y, solver.f

    def _weights(self, x: float) -> np.ndarray:
        """c_j(x) by SciPy's Horner-like recursion (``Dop853DenseOutput``) on the weights."""
        c = np.zeros(INTERPOLATOR_POWER)
        for i in range(INTERPOLATOR_POWER):
            c[INTERPOLATOR_POWER - 1 - i] += 1.0
            c *= x if i % 2 == 0 else 1.0 - x
        return c

    def _coefficients(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At time t: the weights of K's rows, of the extra stages, and of y₀, y and f."""
        if self.solver.steps != self.step:
            raise RuntimeError("the dense output of an earlier step (the stages have changed)")
        c, h = self._weights((t - self.t_old) / self.h), self.h
        a = c[0] - c[1] + 2.0 * c[2]
        w = h * (c[3:] @ self.solver.D)
        w[0] += h * (c[1] - c[2])
        S = self.solver.n_stages + 1
        return _rows(w[:S]), w[S:], np.array([1.0 - a, a, -c[2] * h])

    def at(self, t: float, components: np.ndarray) -> np.ndarray:
        """The interpolant at time t, at the given components only (shape (k,)): a few
        columns of the stages read, not the whole state (the work integral's nodes where the
        power reads few coordinates, :meth:`pfaff.integrate.integrators._RKStepper.work_until`)."""
        s = self.solver
        w, v, coefs = self._coefficients(float(t))
        y = w @ s.K[:, components] + v @ s._extra[:, components]  # type: ignore[index]
        for coef, x in zip(coefs, (self.y_old, self.y, self.f), strict=True):
            y += coef * x[components]
        return y

    def _call_impl(self, t: np.ndarray) -> np.ndarray:
        s = self.solver
        ts = np.atleast_1d(t)
        out = np.empty((len(ts), len(self.y_old)))
        for k, tk in enumerate(ts):
            w, v, coefs = self._coefficients(float(tk))
            if s._jit is not None:
                s._spans(w, s.K, v, s._extra, coefs, self.y_old, self.y, self.f, out[k])
                continue
            np.dot(w, s.K, out=out[k])
            np.dot(v, s._extra, out=s._stage)
            out[k] += s._stage
            for coef, x in zip(coefs, (self.y_old, self.y, self.f), strict=True):
                np.multiply(x, coef, out=s._stage)
                out[k] += s._stage
        return out[0] if np.ndim(t) == 0 else out.T
