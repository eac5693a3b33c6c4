"""The fused scalar kernel of a small system: generated functions and where their outputs go.

Made by :func:`pfaff.derive.fused.build_fused`; used by :class:`pfaff.NumericModel`
(:meth:`~pfaff.numeric.model.NumericModel.use_fused`).

Why it exists (``benchmarks/simulate.py``): for a handful of coordinates the template kernels
spend their time in NumPy's call overhead on arrays of length one; one right-hand side of the
Cartesian pendulum costs about 1.6 µs as ``rfn``, against 6–7 µs for one lambdified kernel and a
LAPACK solve and 90 µs through the template kernels.
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
    rfn : callable or None
        The kernel and the floored range-space solve (:mod:`pfaff.numeric.smallsolve`) in one
        generated function: ``rfn(*params, alpha, beta, *taus, cap, slow)`` returns
        ``rhs(t, y: list) -> [q̇, q̈]`` (a list), which calls ``slow(t, y)`` where M is not
        positive definite. None if the printer could not write the expressions.
    cfn : callable
        ``cfn(*M entries, *A entries, *zeros(n), *r, shift) -> M⁻¹Aᵀ(A M⁻¹Aᵀ + δ²I)⁻¹ r``: the
        projection's correction (:mod:`pfaff.numeric.projection`) as generated code.
    kkt_index, kkt_source : ndarray of int
        ``K.flat[kkt_index] = out[kkt_source]`` fills the symmetric augmented matrix
        [[M, Aᵀ], [A, 0]] of shape (n+m, n+m).
    entry_index : ndarray of int
        ``K.flat[entry_index]`` are the M and A entries, in output (and ``cfn`` argument) order.
    offsets : tuple of int
        Start of the forcing, -bias, b and f blocks in the output (forcing and -bias together are
        the right-hand side of the augmented system).
    """

    fn: Callable
    vfn: Callable
    efn: Callable
    rfn: Callable | None
    cfn: Callable
    kkt_index: np.ndarray
    kkt_source: np.ndarray
    entry_index: np.ndarray
    offsets: tuple[int, int, int, int]

    def entries(self, K: np.ndarray) -> list[float]:
        """The M and A entries of an assembled K, as the arguments of ``cfn``."""
        return K.flat[self.entry_index].tolist()
