"""The fused scalar kernel of a small system: generated functions and where their outputs go.

Made by :func:`pfaff.derive.fused.build_fused`; used by :class:`pfaff.NumericModel`
(:meth:`~pfaff.numeric.model.NumericModel.use_fused`).

Why it exists (``benchmarks/simulate.py``): for a handful of coordinates the template kernels
spend their time in NumPy's call overhead on arrays of length one; one right-hand side of the
Cartesian pendulum costs about 1.6 µs as ``rfn``, against 6–7 µs for one lambdified kernel and a
LAPACK solve and 90 µs through the template kernels.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pfaff.numeric.generated import loaded, portable
from pfaff.numeric.projection import DAMPING, SHRUNK
from pfaff.numeric.protocol import ConstraintLinearization

_FUNCTIONS = ("fn", "vfn", "efn", "rfn", "cfn", "rfn_aug", "pfn", "afn")


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
    cfn : callable or None
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
    arows, acols : tuple of int
        Row and column of each A entry, in output order.
    llvm : callable or None
        ``llvm()`` compiles (on first call, then cached in memory and on disk) the same
        right-hand side as ``rfn`` to machine code and returns ``f(x) -> [q̇, q̈, λ, fn's
        outputs, checks]`` on the flat array ``x = [t, q, q̇, params, alpha, beta, taus,
        cap]``, or None where it cannot (no LLVM in this SymEngine); ``llvm(build=False)`` only loads it from the
        on-disk cache. Non-finite outputs mean "take ``rfn``" (M not positive definite).
        Without a generated solve (``solves`` False: above ``FUSED_LIMIT`` unknowns) it is
        the kernel alone, ``f(x) -> fn's outputs`` on the same ``x``, and the model solves
        with LAPACK (:mod:`pfaff.derive.machine_kernel`).
    rfn_aug : callable or None
        ``rfn`` for a singular M (quaternion coordinates): the same q̈ from M + ρAᵀA;
        ``make(*params, alpha, beta, *taus, cap, rho, slow)``.
    solves : bool
        Whether ``llvm`` is the whole right-hand side (with the solve) or the kernel alone.
    ops : int
        Operations in the generated kernel (operators and calls counted in its printed code):
        a size the evaluator rule reads (:func:`pfaff.numeric.evaluator.choose`).
    pfn : callable or None
        ``pfn(t, q…, q̇…, *params) -> [P]``, the power Qᵀq̇ of the applied forces
        (:mod:`pfaff.derive.fusedpower`), generated on its first call; ``pfn.function()``
        (before it is pickled) makes it and returns it, or None when it cannot be made.
    afn : callable or None
        ``afn(t, q: list, q̇: list, params) -> ([q̈], [λ])`` or None (a check failed, a value
        not finite): a checked ``accelerations()`` on the generated Python (:func:`pfaff.numeric.checkedsolve.fused_accelerations`);
        generated on its first call.
    checks : int
        How many pivot checks end the machine code's outputs (3, or 0 for machine code made
        before they were: :func:`pfaff.numeric.checkedsolve.passes` reads them).
    loop : callable or None
        ``loop(build=True) -> (con, power)``: the machine code the compiled stepping loop calls
        besides ``llvm`` (:mod:`pfaff.derive.loopcode`), made on first call and cached like it;
        None above ``FUSED_LIMIT``. Pickled, it travels made when it was made before (the
        model's pickle makes it where it has machine code: :class:`MadeLoop`), else as None.
    """

    fn: Callable
    vfn: Callable
    efn: Callable
    rfn: Callable | None
    cfn: Callable | None
    kkt_index: np.ndarray
    kkt_source: np.ndarray
    entry_index: np.ndarray
    offsets: tuple[int, int, int, int]
    arows: tuple[int, ...]
    acols: tuple[int, ...]
    llvm: Callable[..., Callable | None] | None = None
    rfn_aug: Callable | None = None
    solves: bool = True
    ops: int = 0
    pfn: Callable | None = None
    afn: Callable | None = None
    checks: int = 0
    loop: Callable[..., tuple | None] | None = None

    def __getstate__(self) -> dict:
        """The generated functions travel as their source (:mod:`pfaff.numeric.generated`);
        machine code travels with the model (:class:`pfaff.numeric.evaluator.MachineCode`)."""
        state = dict(self.__dict__)
        for key in _FUNCTIONS:
            state[key] = portable(state[key])
        state["llvm"] = None
        made = self.loop(build=False) if self.loop is not None else None
        state["loop"] = MadeLoop(made) if made is not None else None
        return state

    def __setstate__(self, state: dict) -> None:
        for key in _FUNCTIONS:
            state[key] = loaded(state[key])
        self.__dict__.update(state)

    def entries(self, K: np.ndarray) -> list[float]:
        """The M and A entries of an assembled K, as the arguments of ``cfn``."""
        return K.flat[self.entry_index].tolist()


class MadeLoop:
    """``loop`` of an unpickled :class:`FusedKernel`: the loop's machine code as it was made
    (SymEngine's LLVM functions pickle as their compiled code), so that a shipped model (a
    sweep's) steps in the compiled loop as the one it was pickled from.

    Examples
    --------
    >>> import pickle
    >>> loop = pickle.loads(pickle.dumps(MadeLoop((None, None))))
    >>> loop(), loop(build=False)
    ((None, None), (None, None))
    """

    def __init__(self, made: tuple) -> None:
        self.made = made

    def __call__(self, build: bool = True) -> tuple:
        return self.made


class FusedLinearization(ConstraintLinearization):
    """:class:`pfaff.numeric.projection.ArrayLinearization` of a small fused model on Python floats.

    The same thresholds and the same damped mass-metric correction, the latter as generated code
    (``cfn``): a projection after each step of the pendulum costs a few microseconds this way,
    against about 90 µs through NumPy arrays of length two (``benchmarks/simulate.py``, the
    2000 s run: 3.2 s against 6.6 s). Where ``cfn`` fails (M not positive definite) the
    corrections come from ``fallback()``, the array linearization at the same state.

    Parameters
    ----------
    fk : FusedKernel
    t : float
    q, qd : list of float
    p : list of float
        Parameter values.
    tol : float
    holonomic : list of bool
    fallback : callable
        ``() -> ConstraintLinearization`` on arrays at the same state.
    """

    def __init__(
        self,
        fk: FusedKernel,
        t: float,
        q: list,
        qd: list,
        p: list,
        tol: float,
        holonomic: list,
        fallback: Callable[[], ConstraintLinearization],
    ) -> None:
        v = fk.fn(t, *q, *qd, *p)
        o0, _, o2, o3 = fk.offsets
        arows = fk.arows
        self.fk, self.fallback, self.entries, self.zeros = fk, fallback, v[:o0], [0.0] * len(q)
        self.a, self.b = v[o0 - len(arows) : o0], v[o2:o3]
        sq = [0.0] * len(holonomic)
        for a, i in zip(self.a, arows):  # noqa: B905 - equal lengths by construction; hot path
            sq[i] += a * a
        top = math.sqrt(max(sq)) or 1e-300
        self.thr = thr = [tol * min(1.0, max(SHRUNK, math.sqrt(x) / top)) for x in sq]
        self.f = f = [x if h else 0.0 for x, h in zip(v[o3:], holonomic)]  # noqa: B905
        self.position_excess = max([abs(x) / y for x, y in zip(f, thr)])  # noqa: B905
        self._velocities(qd)

    def _velocities(self, qd: list) -> None:
        g = list(self.b)
        for a, i, j in zip(self.a, self.fk.arows, self.fk.acols):  # noqa: B905
            g[i] += a * qd[j]
        self.g = g
        self.velocity_excess = max([abs(x) / y for x, y in zip(g, self.thr)])  # noqa: B905

    def _correction(self, r: list) -> list | None:
        try:
            return self.fk.cfn(*self.entries, *self.zeros, *r, DAMPING**2)
        except (ValueError, ZeroDivisionError):  # M not positive definite
            return None

    def corrected_positions(self, q: np.ndarray) -> np.ndarray:
        d = self._correction(self.f)
        return self.fallback().corrected_positions(q) if d is None else q - np.array(d)

    def corrected_velocities(self, qd: np.ndarray) -> np.ndarray:
        d = self._correction(self.g)
        return self.fallback().corrected_velocities(qd) if d is None else qd - np.array(d)

    def with_velocities(self, qd: np.ndarray) -> FusedLinearization:
        self._velocities(qd.tolist())
        return self
