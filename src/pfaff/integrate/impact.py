"""The impulse of an impact: Newton's restitution law on the contact rows, every bilateral
constraint kept, complementarity between the contacts (a small linear complementarity problem).

At an impact the velocities jump, q̇⁺ = q̇⁻ + Δq̇, under impulses Λ of the constraint rows:

    M Δq̇ = A_bᵀ Λ_b + A_cᵀ Λ_c,      A_b q̇⁺ + b_b = 0            (bilateral rows, kept)
    ġ⁺ = ġ⁻ + A_c Δq̇ ≥ −e ġ⁻,  Λ_c ≥ 0,  Λ_c,j (ġ⁺_j + e_j ġ⁻_j) = 0   (each contact row)

with ġ = A_c q̇ + b_c the rates of the gaps (ġ⁻ ≤ 0 closing; a contact already separating asks
only ġ⁺ ≥ 0). :func:`impulse` solves it exactly by enumerating the active sets, smallest first:
for each set S the equality problem (its KKT system) is solved in the least-squares sense, which
gives the minimum-norm Λ where rows are redundant (Δq̇ is unique where M is positive definite on
the admissible motions), and the first set whose Λ_S ≥ 0 and whose inactive contacts do not
penetrate is the solution (unique for a positive definite Delassus matrix A_c M⁻¹ A_cᵀ on the
bilateral constraints). It is meant for the few contacts that close at once (up to
:data:`MAX_CONTACTS`).
"""

from __future__ import annotations

from itertools import combinations
from typing import NamedTuple

import numpy as np

MAX_CONTACTS = 12  # contacts solved at once by enumeration (2^12 small solves at most)


class Impulse(NamedTuple):
    """The result of :func:`impulse`.

    Attributes
    ----------
    dqd : ndarray, shape (n,)
        Δq̇ = q̇⁺ − q̇⁻.
    bilateral : ndarray, shape (m_b,)
        Λ_b, the impulses of the bilateral rows.
    contact : ndarray, shape (k,)
        Λ_c ≥ 0, the impulses of the contact rows (0 off the active set).
    rates : ndarray, shape (k,)
        ġ⁺ of the contact rows.
    work : float
        The work of the impulses, ½ (q̇⁻ + q̇⁺)ᵀ M Δq̇ (≤ 0 for a loss).
    """

    dqd: np.ndarray
    bilateral: np.ndarray
    contact: np.ndarray
    rates: np.ndarray
    work: float


def impulse(
    M: np.ndarray,
    Ab: np.ndarray,
    rb: np.ndarray,
    Ac: np.ndarray,
    rates: np.ndarray,
    restitution: np.ndarray,
    qd: np.ndarray,
) -> Impulse | None:
    """The impulse of an impact (see the module docstring).

    Parameters
    ----------
    M : ndarray, shape (n, n)
        The mass matrix.
    Ab : ndarray, shape (m_b, n)
        The bilateral rows' A.
    rb : ndarray, shape (m_b,)
        Their velocity defect to remove, −(A_b q̇⁻ + b_b) (≈ 0 on a consistent state).
    Ac : ndarray, shape (k, n)
        The contact rows' A (∂gap/∂q).
    rates : ndarray, shape (k,)
        ġ⁻ of the contacts.
    restitution : ndarray, shape (k,)
        Newton's e of each (0 for a contact that comes to rest).
    qd : ndarray, shape (n,)
        q̇⁻.

    Returns
    -------
    Impulse or None
        None when no active set satisfies the conditions (the equations are inconsistent).

    Examples
    --------
    A ball of mass 2 falling at 3 m/s on a floor with e = 0.5 rebounds at 1.5 m/s:

    >>> r = impulse(np.eye(1) * 2, np.zeros((0, 1)), np.zeros(0), np.ones((1, 1)),
    ...             np.array([-3.0]), np.array([0.5]), np.array([-3.0]))
    >>> [round(float(x), 12) for x in (r.dqd[0], r.contact[0], r.rates[0], r.work)]
    [4.5, 9.0, 1.5, -6.75]
    """
    n, mb, k = M.shape[0], Ab.shape[0], Ac.shape[0]
    target = -restitution * np.minimum(rates, 0.0)
    scale = 1.0 + float(np.abs(rates).max(initial=0.0)) + float(np.abs(rb).max(initial=0.0))
    tol_v = 1e-10 * scale
    for size in range(k + 1):
        for S in combinations(range(k), size):
            rows = list(S)
            A = np.vstack([Ab, Ac[rows]])
            K = np.zeros((n + len(A), n + len(A)))
            K[:n, :n], K[:n, n:], K[n:, :n] = M, -A.T, A
            rhs = np.concatenate([np.zeros(n), rb, target[rows] - rates[rows]])
            x = np.linalg.lstsq(K, rhs, rcond=None)[0]
            if np.abs(K @ x - rhs).max(initial=0.0) > 1e-9 * (1.0 + np.abs(rhs).max(initial=0.0)):
                continue  # this set's equations are inconsistent
            dqd, lam = x[:n], x[n + mb :]
            tol_l = 1e-10 * (1.0 + float(np.abs(x[n:]).max(initial=0.0)))
            after = rates + Ac @ dqd
            if (lam < -tol_l).any() or (np.delete(after - target, rows) < -tol_v).any():
                continue
            contact = np.zeros(k)
            contact[rows] = np.maximum(lam, 0.0)
            work = 0.5 * float((2.0 * qd + dqd) @ (M @ dqd))
            return Impulse(dqd, x[n : n + mb], contact, after, work)
    return None
