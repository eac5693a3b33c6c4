"""What a compiled model computes from a state besides the motion: residuals, forces, energies,
power, and the projection onto the constraints (:class:`Quantities`, a part of
:class:`pfaff.numeric.base.StreamModel`). Every method checks its arguments."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sps

from pfaff.numeric.checks import projection_options, real_vector
from pfaff.numeric.projection import newton_projection
from pfaff.numeric.rank import DENSE_LIMIT, null_basis, sparse_null_basis
from pfaff.numeric.streams import add_product, indices, take


class Quantities:
    """The checked evaluations of a stream model other than its solve (see the module docstring)."""

    if TYPE_CHECKING:
        n: int
        m: int
        dyn: list
        con: list

        def __getattr__(self, name: str) -> Any: ...

    def acceleration_residual(self, t: float, q: object, qd: object, qdd: object) -> np.ndarray:
        """A q̈ + Ȧq̇ + ḃ, shape (m,): zero for accelerations that satisfy the constraints."""
        t, q, qd = self._state(t, q, qd)
        qdd = real_vector(qdd, "qdd", self.n)
        avals, bias = self._accel_constraints(t, q, qd)
        return self.a_matvec(avals, qdd) + self._rows_vector(bias)

    def generalized_constraint_force(
        self, t: float, q: object, qd: object, qdd: object
    ) -> np.ndarray:
        """M q̈ - (Q - h), shape (n,): the generalized constraint force Aᵀλ on a motion."""
        t, q, qd = self._state(t, q, qd)
        qdd = real_vector(qdd, "qdd", self.n)
        mvals, f = self._dynamics(t, q, qd)
        return self.matvec(mvals, qdd) - f

    def constraint_force(self, t: float, q: object, lam: object) -> np.ndarray:
        """Aᵀλ, shape (n,)."""
        t, q, qd = self._state(t, q, np.zeros(self.n))
        lam = real_vector(lam, "lam", self.m)
        avals, _ = self._accel_constraints(t, q, qd)
        y, tmp = np.zeros(self.n), self.scratch()
        for part, vals in zip(self.con, avals, strict=True):
            for c, val in zip(part.cols, vals, strict=True):
                add_product(y, c, val, take(part.rows, lam), tmp)
        return y

    def energy(self, t: float, q: object, qd: object) -> tuple[float, float]:
        """Kinetic and potential energy (T, V)."""
        t, q, qd = self._state(t, q, qd)
        TV = [part.energy(t, q, qd) for part in self.dyn]
        return float(sum(x for x, _ in TV)), float(sum(v for _, v in TV))

    @property
    def applied_power(self) -> bool:
        """True when some applied force can do work (see :meth:`power`)."""
        return any(part.has_power for part in self.dyn)

    def power(self, t: float, q: object, qd: object) -> float:
        """Power of the applied forces, Qᵀq̇: the rate of the work W_nc in the energy balance."""
        t, q, qd = self._state(t, q, qd)
        return self.power_function()(t, q, qd)

    def power_function(self) -> Callable[[float, np.ndarray, np.ndarray], float]:
        """:meth:`power` without the argument checks, for an integrator's checked states
        (:class:`StreamPower`: it names the coordinates it reads)."""
        return StreamPower([part for part in self.dyn if part.has_power])

    def project(
        self, t: float, q: object, qd: object, *, tol: float = 1e-12, max_iter: int = 10
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """Project (q, q̇) onto f(q, t) = 0 and A q̇ + b = 0, mass-orthogonally.

        The projection the integrators use (:func:`pfaff.numeric.projection.newton_projection`)
        at one state: Newton on the positions, then the velocities. Returns the new q, q̇ and
        the number of Newton steps (1 when only the velocities moved; 0: nothing changed).

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> q, qd, steps = model.project(0.0, [0.6, -0.9], [1.0, 1.0])
        >>> bool(abs(q @ q - 1) < 1e-12 and abs(q @ qd) < 1e-12), steps > 0
        (True, True)
        """
        t, q, qd = self._state(t, q, qd)
        tol, max_iter = projection_options(tol, max_iter)
        if not self.m:
            return q, qd, 0
        return newton_projection(
            lambda q_, qd_: self.linearize_constraints(t, q_, qd_, tol), q, qd, max_iter=max_iter
        )

    def redundancy(self, t: float, q: object, qd: object) -> tuple[list[str], np.ndarray]:
        """The constraints and the indeterminate directions of their multipliers at a state.

        Returns
        -------
        names : list of str
            The constraint names, in row order.
        basis : ndarray, shape (m, k)
            An orthonormal basis of the null space of Aᵀ: λ + basis @ c gives the same
            generalized constraint force Aᵀλ for every c, so on these directions only Aᵀλ is
            determined (pfaff reports the minimum-norm λ, orthogonal to them). k = 0: none.

        Examples
        --------
        >>> import warnings, numpy as np, pfaff
        >>> warnings.simplefilter("ignore", pfaff.RedundancyWarning)
        >>> ring = pfaff.models.rolling_ring(4, force=True, closed=True)
        >>> model = ring.equations().compile({"M": 1, "r": 0.5, "F": 2})
        >>> q, qd = pfaff.models.ring_state(4, radius=0.5, theta=0.3)
        >>> names, basis = model.redundancy(0.0, q, qd)
        >>> basis.shape, np.round(np.abs(basis[:, 0]) * 2, 6).tolist()  # the hoop stress
        ((5, 1), [0.0, 1.0, 1.0, 1.0, 1.0])
        """
        t, q, qd = self._state(t, q, qd)
        A = self.constraint_matrix(t, q)
        names = list(self.constraint_names)
        if sps.issparse(A) and A.shape[0] > DENSE_LIMIT:
            return names, sparse_null_basis(sps.csr_matrix(A))
        return names, null_basis(A)


class StreamPower:
    """P(t, q, q̇) = Σ Q_a q̇_a of the blocks with applied forces, unchecked.

    Attributes
    ----------
    coordinates : ndarray of int
        The indices of q (and the same of q̇) it reads: the columns of those blocks (the ring's
        push: x alone), so that an integrator may give it states exact there only (the dense
        output at the work integral's nodes, :mod:`pfaff.integrate.work`).

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> ring = pfaff.models.rolling_ring(4, force=True, family=True).equations().compile(
    ...     {"M": 2, "r": 0.5, "F": 3})
    >>> power = ring.power_function()
    >>> power.coordinates.tolist(), power(0.0, np.zeros(5), np.full(5, 2.0))  # F ẋ
    ([0], 6.0)
    """

    def __init__(self, parts: list) -> None:
        self.parts = parts
        cols = [indices(c) for part in parts for c in part.kernel.columns]
        self.coordinates = np.unique(np.concatenate(cols)) if cols else np.zeros(0, np.int64)

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        return math.fsum(part.power(t, q, qd) for part in self.parts)
