"""The fused scalar kernel of a small system: generated functions and where their outputs go.

Made by :func:`pfaff.derive.fused.build_fused`; used by :class:`pfaff.NumericModel`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FusedKernel:
    """Flat outputs ``[M upper..., A entries..., Q - h (n), -bias (m), b (m), f (m)]`` and slots.

    Attributes
    ----------
    fn : callable
        ``fn(t, q_0..q_{n-1}, qd_0..qd_{n-1}, *params) -> list of float``.
    vfn : callable
        The same outputs with NumPy, vectorized over many states (arguments of shape (k,)).
    efn : callable
        ``[T, V, T(q, 0, t)]``, vectorized like ``vfn``.
    kfn : callable
        ``kfn(t, q.., qd.., *params, alpha, beta) -> (K as nested lists, rhs list)``: the augmented
        system with the Baumgarte-stabilized constraint rows −bias − 2α(A q̇ + b) − β² f, ready
        for LAPACK (the ODE right-hand side of small systems).
    ofn, sfn : callable
        ``ofn`` (same arguments as ``kfn``) gives the flat [M entries, A entries, Q − h, c] and
        ``sfn(*that, *taus, cap)`` q̈ by straight-line Schur-complement code with the pivots of
        A M⁻¹Aᵀ floored (:mod:`pfaff.numeric.smallsolve`, :mod:`pfaff.numeric.kkt`).
    rfn : callable or None
        Both in one generated function: ``rfn(*params, alpha, beta, *taus, cap, slow)`` returns
        ``rhs(t, y: list) -> [q̇, q̈]`` (a list), which calls ``slow(t, y)`` where M is not
        positive definite. None if the printer could not write the expressions.
    qfn, cfn : callable
        Small-system projection in plain Python:
        ``qfn(t, q.., qd.., *params) -> [M entries..., A entries..., f..., g...]`` and
        ``cfn(*M entries, *A entries, *zeros(n), *r, shift) -> M⁻¹Aᵀ(A M⁻¹Aᵀ + δ²I)⁻¹ r``.
    kkt_index, kkt_source : ndarray of int
        ``K.flat[kkt_index] = out[kkt_source]`` fills the symmetric augmented matrix
        [[M, Aᵀ], [A, 0]] of shape (n+m, n+m).
    offsets : tuple of int
        Start of the forcing, -bias, b and f blocks in the output (forcing and -bias together are
        the right-hand side of the augmented system).
    arows : tuple of int
        The row of A of each A entry, in output order.
    """

    fn: Callable
    vfn: Callable
    efn: Callable
    kfn: Callable
    ofn: Callable
    sfn: Callable
    rfn: Callable | None
    qfn: Callable
    cfn: Callable
    kkt_index: np.ndarray
    kkt_source: np.ndarray
    offsets: tuple[int, int, int, int]
    arows: tuple[int, ...]
