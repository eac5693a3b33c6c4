"""Integrate stage: the compiled stepping loop's code, in numba (imported only when the loop runs).

:func:`advance` takes DOP853 steps (the tableau, error norm and step-size controller of
:class:`pfaff.integrate.fastrk.FloatDOP853`), projects each step's end onto the constraints
(:func:`pfaff.numeric.projection.newton_projection`'s policy with the mass-metric correction of
:class:`pfaff.numeric.fused.FusedLinearization`), integrates the work of the applied forces
(the method's own quadrature over a step, four Gauss–Legendre nodes on the dense output up to a
reported time), and writes the reported states (at ``t_eval`` from the dense output, projected;
else every step's end) into arrays. The model's functions are machine code called through their
C entry points (:mod:`pfaff.numeric.machineloop`): nothing returns to Python inside a call.

Whatever the Python path would treat in its own way (non-finite values, M not positive
definite, a projection that cannot reach the constraints, a step size underflowing, an
overflowing power) ends the call with :data:`BAIL` at the start of that step, every array as it
was before it: the driver takes that step in Python, which then fails, or falls back, exactly as
it always did.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.integrate import DOP853

from pfaff.integrate.events import SINGULAR
from pfaff.integrate.fastrk import _EXPONENT, MAX_FACTOR, MIN_FACTOR, SAFETY
from pfaff.integrate.loopbase import cached, call_entry, copy_into, helper, inlined
from pfaff.integrate.loopproject import project
from pfaff.integrate.pace import COLLAPSE, EPS, ULPS, WINDOW
from pfaff.integrate.work import GAUSS_W, GAUSS_X

# what advance returns: the span's end, the budget used (or a window for the driver's Pace to
# judge), a step for the Python path, a failed window (the Pace's failure, its last step taken)
END, MORE, BAIL, STALL = 0, 1, 2, 3
# the run's float state and integer counters (indices into ``s`` and ``c``)
T, H, T_BOUND, MAX_STEP, RTOL, TOL, WORK, UNREACHED, START, LARGEST, LAST_T = range(11)
NFEV, STEPS, REJECTED, RESTARTS, PROJECTIONS, ITERATIONS, K_EVAL, N_OUT, N_STEP = range(9)
BUDGET, MAX_ITER, FLAGS, PACE_STEPS, PACE_COUNT = range(9, 14)
HAS_TE, PROJECT_OUT, HAS_POWER, QUIET, HAS_BEFORE = 1, 2, 4, 8, 16  # bits of c[FLAGS]


def _nonzero(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each row's nonzero coefficients, in column order, and their columns (a row's sums run
    over these only, as FloatDOP853's generated code writes them), zero-padded; the last
    column holds the row's count."""
    coefs, cols = np.zeros(rows.shape), np.zeros((len(rows), rows.shape[1] + 1), dtype=np.int64)
    for r, row in enumerate(rows):
        (nz,) = np.nonzero(row)
        coefs[r, : nz.size], cols[r, : nz.size], cols[r, -1] = row[nz], nz, nz.size
    return coefs, cols


TABLEAU = (
    *_nonzero(DOP853.A), *_nonzero(DOP853.B[None, :]), np.array(DOP853.C, dtype=float),
    *_nonzero(np.vstack([DOP853.E5, DOP853.E3])), *_nonzero(DOP853.A_EXTRA),
    np.array(DOP853.C_EXTRA, dtype=float), np.ascontiguousarray(DOP853.D, dtype=float),
    np.array(GAUSS_X, dtype=float), np.array(GAUSS_W, dtype=float),
)  # fmt: skip
# (A, its columns, B, its columns, C, [E5; E3], their columns, A_EXTRA, its columns, C_EXTRA,
# D, the Gauss nodes and weights)
A_, AJ, B_, BJ, C_, E_, EJ, AX, AXJ, CX, D_, GX, GW = range(13)


@inlined
def _rhs(fns, rin, rout, t, y, k):
    """k = [q̇, q̈] at (t, y); False where they are not finite (their sum, as
    :func:`pfaff.numeric.evaluator.machine_rhs` tests them)."""
    n2 = y.size
    rin[0] = t
    for i in range(n2):
        rin[1 + i] = y[i]
    call_entry(fns[0], rout, rin, fns[1])
    total = 0.0
    for i in range(n2):
        v = rout[i]
        total += v
        k[i] = v
    return math.isfinite(total)


@inlined
def _combine(y, h, coefs, cols, K, out):
    """out = y + h Σ_j coefs[j] K[cols[j]] over a row's nonzero coefficients (``cols[-1]`` of
    them), each sum in column order: the sums of FloatDOP853's generated code. The components'
    sums advance together (each one's additions in the same order as alone: the same result),
    the first term written rather than added to zeros (no call of ``memset``): one sum at a
    time waited on each addition (an attempt with its 13 right-hand sides of the Cartesian
    pendulum took about 0.93 µs that way, 0.72 µs this way)."""
    count, n2 = cols[cols.size - 1], y.size
    if count == 0:
        for i in range(n2):
            out[i] = y[i] + h * 0.0
        return
    c, row = coefs[0], cols[0]
    for i in range(n2):
        out[i] = 0.0 + c * K[row, i]
    for j in range(1, count):
        c, row = coefs[j], cols[j]
        for i in range(n2):
            out[i] += c * K[row, i]
    for i in range(n2):
        out[i] = y[i] + h * out[i]


@helper
def _attempt(fns, rin, rout, tab, t, h, y, K, Ys, yn):
    """One DOP853 attempt from (t, y) with K[0] = f: the stages K[1..12], their states Ys and
    the new state yn; False where a stage is not finite."""
    A, AJ_, C = tab[A_], tab[AJ], tab[C_]
    copy_into(y, Ys[0])
    for s in range(1, 12):
        _combine(y, h, A[s], AJ_[s], K, Ys[s])
        if not _rhs(fns, rin, rout, t + C[s] * h, Ys[s], K[s]):
            return False
    _combine(y, h, tab[B_][0], tab[BJ][0], K, yn)
    return _rhs(fns, rin, rout, t + h, yn, K[12])


@helper
def _error(tab, K, y, yn, atol, rtol, h_abs, a, b):
    """DOP853's error norm of the attempt (SciPy's, as FloatDOP853 computes it); ``a``, ``b``
    scratch of shape (2n,)."""
    E, EJ_ = tab[E_], tab[EJ]
    n2, n5, n3 = y.size, EJ_[0, 13], EJ_[1, 13]
    for i in range(n2):
        a[i] = b[i] = 0.0
    for j in range(n5):  # (the components' sums together, as in _combine)
        c, row = E[0, j], EJ_[0, j]
        for i in range(n2):
            a[i] += c * K[row, i]
    for j in range(n3):
        c, row = E[1, j], EJ_[1, j]
        for i in range(n2):
            b[i] += c * K[row, i]
    s5 = s3 = 0.0
    for i in range(n2):
        sc = atol[i] + max(abs(y[i]), abs(yn[i])) * rtol
        x5, x3 = a[i] / sc, b[i] / sc
        s5 += x5 * x5
        s3 += x3 * x3
    if s5 == 0.0 and s3 == 0.0:
        return 0.0
    return h_abs * s5 / math.sqrt(n2 * (s5 + 0.01 * s3))


@helper
def _power(fns, cin, pout, t, y):
    cin[0] = t
    for i in range(y.size):
        cin[1 + i] = y[i]
    call_entry(fns[4], pout, cin, fns[5])
    return pout[0]


@helper
def _sum(terms, count):
    """Neumaier's compensated sum of ``terms[:count]`` (the Python path's ``math.fsum``); NaN
    when a term is not finite or overflows (``integrate.work.checked_sum`` fails there)."""
    total = comp = 0.0
    for i in range(count):
        v = terms[i]
        if not (math.isfinite(v) and abs(v) < 1e300):
            return np.nan
        s = total + v
        comp += (total - s) + v if abs(total) >= abs(v) else (v - s) + total
        total = s
    return total + comp


@helper
def _step_work(fns, cin, pout, tab, t, h, Ys, terms):
    """∫ P dt over the step by the method's quadrature, h Σ b_i P(t_i, y_i)."""
    B, BJ_, C = tab[B_][0], tab[BJ][0], tab[C_]
    count = BJ_[12]
    for k in range(count):
        i = BJ_[k]
        terms[k] = B[k] * _power(fns, cin, pout, t + C[i] * h, Ys[i])
    return h * _sum(terms, count)


@helper
def _dense_coefficients(fns, rin, rout, tab, t, h, y0, y1, K, F, tmp):
    """The 7th-degree interpolant of the step (three more stages): F as SciPy forms it."""
    AXs, AXJ_, CXs, D = tab[AX], tab[AXJ], tab[CX], tab[D_]
    n2 = y0.size
    for e in range(3):
        s = 13 + e
        _combine(y0, h, AXs[e], AXJ_[e], K, tmp)
        if not _rhs(fns, rin, rout, t + CXs[e] * h, tmp, K[s]):
            return False
    for i in range(n2):
        dy = y1[i] - y0[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[12, i] + K[0, i])
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += D[r, j] * K[j, i]
            F[3 + r, i] = h * acc
    return True


@helper
def _dense_at(F, y0, t_old, h, t, out):
    """The interpolant at t (SciPy's evaluation of F, highest row first)."""
    x = (t - t_old) / h
    for i in range(y0.size):
        v = 0.0
        for r in range(7):
            v += F[6 - r, i]
            v *= x if r % 2 == 0 else 1.0 - x
        out[i] = v + y0[i]


@helper
def _dense_work(fns, cin, pout, tab, F, y0, t_old, h, b, tmp, terms):
    """∫ P dt from the step's start to ``b`` inside it: four Gauss–Legendre nodes on the dense
    output (:func:`pfaff.integrate.work.dense_work`)."""
    GXs, GWs = tab[GX], tab[GW]
    if b <= t_old:
        return 0.0
    for k in range(4):
        tk = t_old + (b - t_old) * (GXs[k] + 1.0) / 2.0
        _dense_at(F, y0, t_old, h, tk, tmp)
        terms[k] = GWs[k] * _power(fns, cin, pout, tk, tmp)
    return 0.5 * (b - t_old) * _sum(terms, 4)


@helper
def _angles(euler, y, out):
    """sin (a symmetric sequence, 3-1-3) or cos (3-2-1) of each Euler set's second angle."""
    for e in range(euler.shape[0]):
        v = y[euler[e, 0]]
        out[e] = math.sin(v) if euler[e, 1] else math.cos(v)


@helper
def _singular(euler, y, before, has_before):
    """Whether some Euler set is at its singularity at y or crossed it since ``before``
    (:meth:`pfaff.integrate.events.AttitudeEvents.singular`)."""
    for e in range(euler.shape[0]):
        v = y[euler[e, 0]]
        value = math.sin(v) if euler[e, 1] else math.cos(v)
        if abs(value) < SINGULAR or (has_before and value * before[e] < 0):
            return True
    return False


class Work(NamedTuple):
    """Scratch arrays of one run (made once by :func:`workspace`)."""

    K: np.ndarray  # (16, 2n): the stages, three more for the dense output
    Ys: np.ndarray  # (12, 2n): the stage states
    yn: np.ndarray  # (2n,): the step's end as computed
    yp: np.ndarray  # (2n,): the step's end projected
    fp: np.ndarray  # (2n,): the derivative there
    yd: np.ndarray  # (2n,): a dense-output state
    tmp: np.ndarray  # (2n,)
    F: np.ndarray  # (7, 2n): the interpolant's coefficients
    terms: np.ndarray  # (12,): a quadrature's terms
    M: np.ndarray  # (n, n)
    A: np.ndarray  # (m, n)
    LM: np.ndarray  # (n, n)
    Z: np.ndarray  # (m, n)
    S: np.ndarray  # (m, m)
    LS: np.ndarray  # (m, m)
    b: np.ndarray  # (m,)
    f: np.ndarray  # (m,)
    g: np.ndarray  # (m,)
    thr: np.ndarray  # (m,)
    lam: np.ndarray  # (m,)
    delta: np.ndarray  # (n,)
    angles: np.ndarray  # (e,): the Euler sets' tested function at the last step's end


def workspace(n: int, m: int, e: int = 0) -> Work:
    """The scratch arrays of a system of n coordinates, m constraints and e Euler sets.

    Examples
    --------
    >>> w = workspace(2, 1)
    >>> w.K.shape, w.M.shape, w.A.shape, w.angles.shape
    ((16, 4), (2, 2), (1, 2), (0,))
    """
    n2 = 2 * n
    vec = [np.zeros(n2) for _ in range(5)]
    return Work(
        np.zeros((16, n2)), np.zeros((12, n2)), *vec, np.zeros((7, n2)), np.zeros(12),
        np.zeros((n, n)), np.zeros((m, n)), np.zeros((n, n)), np.zeros((m, n)),
        np.zeros((m, m)), np.zeros((m, m)), *(np.zeros(m) for _ in range(5)), np.zeros(n),
        np.zeros(e),
    )  # fmt: skip


@cached
def advance(fns, rin, rout, cin, cout, pout, mass, acon, hol, tab, s, c, atol, y, f, te,
            out_t, out_y, out_w, euler, w):  # fmt: skip
    """Take steps from (s[T], y, f) until the span's end (:data:`END`), ``c[BUDGET]`` steps or
    a full window the driver judges (:data:`MORE`), a step the Python path must take
    (:data:`BAIL`) or a window that fails the pace's test (:data:`STALL`).

    Every accepted step updates y (projected), f, s[T], s[H], s[WORK], the counters in ``c``
    and the pace's history (:class:`pfaff.integrate.pace.Pace`: its steps, window and largest
    step); each reported state goes to ``out_t``, ``out_y``, ``out_w`` (``c[N_OUT]`` of them).
    A step that bails changes nothing.
    """
    flags = c[FLAGS]
    has_te, project_out, has_power = flags & HAS_TE, flags & PROJECT_OUT, flags & HAS_POWER
    m = hol.size
    K, Ys, yn, yp, fp, yd = w.K, w.Ys, w.yn, w.yp, w.fp, w.yd
    tol, max_iter = s[TOL], c[MAX_ITER]
    while c[N_STEP] < c[BUDGET]:
        t = s[T]
        if t >= s[T_BOUND]:
            return END
        if not has_te and c[N_OUT] >= out_t.size:
            return MORE
        # ---- one accepted step (FloatDOP853._step_impl)
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = min(max(s[H], min_step), s[MAX_STEP])
        rejected, nfev, nrej = False, 0, 0
        copy_into(f, K[0])
        while True:
            if h_abs < min_step:
                return BAIL
            t_new = t + h_abs
            if t_new - s[T_BOUND] > 0:
                t_new = s[T_BOUND]
            h = t_new - t
            h_abs = abs(h)
            nfev += 12
            if not _attempt(fns, rin, rout, tab, t, h, y, K, Ys, yn):
                return BAIL
            err = _error(tab, K, y, yn, atol, s[RTOL], h_abs, w.tmp, yd)
            if err < 1.0:
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**_EXPONENT)
                h_next = h_abs * (min(1.0, factor) if rejected else factor)
                break
            h_abs *= max(MIN_FACTOR, SAFETY * err**_EXPONENT)
            rejected, nrej = True, nrej + 1
        # ---- the work over it, the reported times inside it, its projected end
        step_work = 0.0
        if has_power:
            step_work = _step_work(fns, cin, pout, tab, t, h, Ys, w.terms)
            if not math.isfinite(step_work):
                return BAIL
        k, n_out, proj, iters = c[K_EVAL], c[N_OUT], 0, 0
        dense = False
        while has_te and k < te.size and te[k] <= t_new:
            if not dense:
                nfev += 3
                if not _dense_coefficients(fns, rin, rout, tab, t, h, y, yn, K, w.F, w.tmp):
                    return BAIL
                dense = True
            _dense_at(w.F, y, t, h, te[k], yd)
            wk = 0.0
            if has_power:
                wk = _dense_work(fns, cin, pout, tab, w.F, y, t, h, te[k], w.tmp, w.terms)
                if not math.isfinite(wk):
                    return BAIL
            if project_out and m:
                it, _ = project(fns, cin, cout, mass, acon, hol, te[k], yd, tol, max_iter, w)
                if it < 0:
                    return BAIL
                if it:
                    proj, iters = proj + 1, iters + it
            out_t[n_out] = te[k]
            copy_into(yd, out_y[n_out])
            out_w[n_out] = s[WORK] + wk
            n_out += 1
            k += 1
        copy_into(yn, yp)
        changed = 0
        if m:
            it, reached = project(fns, cin, cout, mass, acon, hol, t_new, yp, tol, max_iter, w)
            if it < 0 or (it and reached > s[UNREACHED] * tol):
                return BAIL
            changed = 1 if it else 0
            if it:
                proj, iters = proj + 1, iters + it
        if changed:
            if not _rhs(fns, rin, rout, t_new, yp, fp):  # the FSAL stage restarted
                return BAIL
        else:
            copy_into(K[12], fp)
        if not has_te:
            out_t[n_out] = t_new
            copy_into(yp, out_y[n_out])
            out_w[n_out] = s[WORK] + step_work
            n_out += 1
        if euler.shape[0] and _singular(euler, yp, w.angles, c[FLAGS] & HAS_BEFORE):
            return BAIL  # the Python path takes this step, and stops the run after it
        # ---- commit
        copy_into(yp, y)
        copy_into(fp, f)
        s[T], s[H], s[WORK] = t_new, h_next, s[WORK] + step_work
        c[NFEV] += nfev
        c[STEPS] += 1
        c[REJECTED] += nrej
        c[RESTARTS] += changed
        c[PROJECTIONS] += proj
        c[ITERATIONS] += iters
        c[K_EVAL], c[N_OUT] = k, n_out
        c[N_STEP] += 1
        if euler.shape[0]:
            _angles(euler, y, w.angles)
            c[FLAGS] |= HAS_BEFORE
        s[LAST_T] = t
        # ---- the pace (integrate.pace.Pace.step): a full window is judged here when only a
        # failure can come of it, else by the driver
        c[PACE_STEPS] += 1
        if c[PACE_COUNT] == 0:
            s[START] = t
        c[PACE_COUNT] += 1
        s[LARGEST] = max(s[LARGEST], t_new - t)
        if c[PACE_COUNT] >= WINDOW:
            if not flags & QUIET:
                return MORE
            mean = (t_new - s[START]) / c[PACE_COUNT]
            if mean < COLLAPSE * s[LARGEST] or mean <= ULPS * EPS * abs(t_new):
                return STALL
            c[PACE_COUNT] = 0
    return END if s[T] >= s[T_BOUND] else MORE
