"""Integrate stage: the compiled loop's projection onto the constraints (numba).

:func:`pfaff.numeric.projection.newton_projection`'s policy with the mass-metric correction of
:class:`pfaff.numeric.fused.FusedLinearization` (``cfn``), on the entries of M and A that the
model's ``con`` machine code gives (:mod:`pfaff.derive.loopcode`); where the Python path would
correct on arrays instead (M or the damped A M⁻¹Aᵀ not positive definite, a non-finite value),
these functions say so and the loop leaves the step to it.
"""

from __future__ import annotations

import math

import numpy as np

from pfaff.integrate.loopbase import call_entry, copy_into, helper
from pfaff.numeric.projection import DAMPING, SHRUNK

SHIFT = DAMPING**2


@helper
def _linearize(fns, cin, cout, mass, acon, hol, t, y, tol, M, A, b, f, thr):
    """M, A, b, f (holonomic rows) and the rows' thresholds at (t, y); the position excess
    max |f_i| / thr_i, or −1 where the constraint code is not finite."""
    n2, m = y.size, hol.size
    cin[0] = t
    for i in range(n2):
        cin[1 + i] = y[i]
    call_entry(fns[2], cout, cin, fns[3])
    for i in range(cout.size):
        if not math.isfinite(cout[i]):
            return -1.0
    nM, nA = mass.shape[0], acon.shape[0]  # (M and A are zero outside their patterns)
    for s in range(nM):
        M[mass[s, 0], mass[s, 1]] = M[mass[s, 1], mass[s, 0]] = cout[s]
    top = 0.0
    for i in range(m):
        thr[i] = 0.0  # (the squared row norm, for now)
    for s in range(nA):
        a = cout[nM + s]
        A[acon[s, 0], acon[s, 1]] = a
        thr[acon[s, 0]] += a * a
    for i in range(m):
        top = max(top, thr[i])
    top = math.sqrt(top)
    if top == 0.0:
        top = 1e-300
    excess = 0.0
    for i in range(m):
        thr[i] = tol * min(1.0, max(SHRUNK, math.sqrt(thr[i]) / top))
        b[i] = cout[nM + nA + i]
        f[i] = cout[nM + nA + m + i] if hol[i] != 0.0 else 0.0
        excess = max(excess, abs(f[i]) / thr[i])
    return excess


@helper
def _velocities(acon, cout, b, y, thr, g):
    """g = A q̇ + b (A's entries in ``con``'s order) and the velocity excess max |g_i| / thr_i."""
    n, m, nA = y.size // 2, b.size, acon.shape[0]
    nM = cout.size - nA - 2 * m
    copy_into(b, g)
    for s in range(nA):
        g[acon[s, 0]] += cout[nM + s] * y[n + acon[s, 1]]
    excess = 0.0
    for i in range(m):
        excess = max(excess, abs(g[i]) / thr[i])
    return excess


@helper
def _cholesky(S, L):
    """L Lᵀ = S; False where a pivot is not positive (the generated code fails there)."""
    k = S.shape[0]
    for j in range(k):
        d = S[j, j]
        for p in range(j):
            d -= L[j, p] * L[j, p]
        if not d > 0.0:
            return False
        L[j, j] = math.sqrt(d)
        for i in range(j + 1, k):
            v = S[i, j]
            for p in range(j):
                v -= L[i, p] * L[j, p]
            L[i, j] = v / L[j, j]
    return True


@helper
def _solve(L, x):
    """x ← (L Lᵀ)⁻¹ x in place."""
    k = L.shape[0]
    for i in range(k):
        v = x[i]
        for p in range(i):
            v -= L[i, p] * x[p]
        x[i] = v / L[i, i]
    for i in range(k - 1, -1, -1):
        v = x[i]
        for p in range(i + 1, k):
            v -= L[p, i] * x[p]
        x[i] = v / L[i, i]


@helper
def _correction(M, A, r, LM, Z, S, LS, lam, out):
    """out = M⁻¹Aᵀ(A M⁻¹Aᵀ + δ²·tr·I)⁻¹ r (``FusedKernel.cfn``); False where M or the damped
    A M⁻¹Aᵀ is not positive definite (the Python path then corrects on arrays)."""
    n, m = M.shape[0], A.shape[0]
    if not _cholesky(M, LM):
        return False
    for r_ in range(m):
        copy_into(A[r_], Z[r_])
        _solve(LM, Z[r_])
    tr = 0.0
    for i in range(m):
        for j in range(i + 1):
            v = 0.0
            for k in range(n):
                v += A[i, k] * Z[j, k]
            S[i, j] = S[j, i] = v
        tr += S[i, i]
    for i in range(m):
        S[i, i] += SHIFT * tr
    if not _cholesky(S, LS):
        return False
    copy_into(r, lam)
    _solve(LS, lam)
    for i in range(n):
        v = 0.0
        for k in range(m):
            v += Z[k, i] * lam[k]
        out[i] = v
    return True


@helper
def project(fns, cin, cout, mass, acon, hol, t, y, tol, max_iter, w):
    """Project y = [q, q̇] in place (``newton_projection``): (iterations, 0 nothing changed,
    −1 bail; the residual max(|f|, |g|) reached)."""
    M, A, LM, Z, S, LS = w.M, w.A, w.LM, w.Z, w.S, w.LS
    b, f, g, thr, lam, delta = w.b, w.f, w.g, w.thr, w.lam, w.delta
    n = y.size // 2
    pe = _linearize(fns, cin, cout, mass, acon, hol, t, y, tol, M, A, b, f, thr)
    if pe < 0.0:
        return -1, 0.0
    ve = _velocities(acon, cout, b, y, thr, g)
    if max(pe, ve) <= 1.0:
        return 0, 0.0
    it, last = 0, np.inf
    while pe > 1.0 and it < max_iter and pe < last:
        if not _correction(M, A, f, LM, Z, S, LS, lam, delta):
            return -1, 0.0
        for i in range(n):
            y[i] -= delta[i]
        it, last = it + 1, pe
        pe = _linearize(fns, cin, cout, mass, acon, hol, t, y, tol, M, A, b, f, thr)
        if pe < 0.0:
            return -1, 0.0
        ve = _velocities(acon, cout, b, y, thr, g)
    last = np.inf
    for _ in range(max(max_iter, 1)):
        if ve <= 1.0 or ve >= last:
            break
        if not _correction(M, A, g, LM, Z, S, LS, lam, delta):
            return -1, 0.0
        for i in range(n):
            y[n + i] -= delta[i]
        last = ve
        ve = _velocities(acon, cout, b, y, thr, g)
    reached = 0.0
    for i in range(hol.size):
        reached = max(reached, abs(f[i]), abs(g[i]))
    return max(it, 1), reached
