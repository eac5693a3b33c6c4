"""A trajectory with its sensitivities: ∂(q, q̇)/∂p and ∂λ/∂p at every reported time."""

from __future__ import annotations

from typing import Any

import numpy as np

from pfaff.core.errors import ConstraintError
from pfaff.results.trajectory import Trajectory


class SensitivityTrajectory(Trajectory):
    """A :class:`Trajectory` with the derivatives of its states by parameters and initial values.

    Attributes
    ----------
    sensitivity : ndarray, shape (k, 2n, n_s)
        ``[i, :n, j]`` = ∂q(t_i)/∂s_j and ``[i, n:, j]`` = ∂q̇(t_i)/∂s_j for the columns s listed
        in :attr:`sensitivity_labels`.
    sensitivity_labels : list of str
        The parameters' names, then (``initial=True``) ``"q0.<name>"`` and ``"qd0.<name>"`` for
        every coordinate.
    multiplier_sensitivity : ndarray, shape (k, m, n_s)
        ∂λ(t_i)/∂s_j; refused (:class:`pfaff.ConstraintError`) for a run with redundant
        constraint rows, where λ itself is not determined.

    Examples
    --------
    >>> import pfaff
    >>> model = pfaff.models.pendulum().equations().compile({"L": 1.0, "g": 9.81, "m": 1.0})
    >>> run = pfaff.sensitivities(model, [0.1], [0.0], (0, 1), parameters=["L"])
    >>> run.sensitivity.shape, run.sensitivity_labels
    ((..., 2, 1), ['L'])
    """

    @classmethod
    def of(cls, traj: Trajectory, **fields: Any) -> SensitivityTrajectory:
        """``traj`` with the sensitivity fields (its arrays shared, not copied)."""
        out = cls.__new__(cls)
        out.__dict__.update(traj.__dict__)
        out.sensitivity = fields["sensitivity"]
        out.sensitivity_labels = list(fields["sensitivity_labels"])
        out._multiplier_sensitivity = fields["multiplier_sensitivity"]
        return out

    @property
    def multiplier_sensitivity(self) -> np.ndarray:
        """∂λ/∂s at every reported time, shape (k, m, n_s)."""
        if self._multiplier_sensitivity is None:
            raise ConstraintError(
                "multiplier_sensitivity is undefined for this run: its constraint rows are "
                "redundant, so λ (and its derivative) is not determined; only Aᵀλ is"
            )
        return self._multiplier_sensitivity
