"""Consistent initial states: complete (q, q̇) from the independent coordinates and speeds."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import ConstraintError, StateError
from pfaff.core.keywords import checked_keywords
from pfaff.numeric.checks import check_model, check_state, projection_options
from pfaff.numeric.projection import ArrayLinearization, newton_projection
from pfaff.numeric.protocol import DynamicsModel


def _indices(
    model: DynamicsModel, independent: Sequence[int | str], arg: str = "independent"
) -> np.ndarray:
    names = list(model.coordinate_names)
    out = []
    if isinstance(independent, str | bytes) or not hasattr(independent, "__iter__"):
        raise StateError(
            f"`{arg}` must be a sequence of coordinate names or indices; got {independent!r:.80}"
        )
    for c in independent:
        if isinstance(c, str):
            if c not in names:
                raise StateError(
                    f"unknown coordinate `{c}` in `{arg}` (have {', '.join(names[:8])})"
                )
            out.append(names.index(c))
        elif isinstance(c, int | np.integer) and not isinstance(c, bool) and 0 <= int(c) < model.n:
            out.append(int(c))
        else:
            raise StateError(f"`{arg}` entries must be coordinate names or indices; got {c!r:.80}")
    if len(set(out)) != len(out):
        raise StateError(f"`{arg}` lists a coordinate twice")
    return np.array(sorted(out), dtype=np.int64)


def _dense(A: np.ndarray | sps.spmatrix) -> np.ndarray:
    return A.toarray() if sps.issparse(A) else np.asarray(A)


@checked_keywords
def consistent_state(
    model: DynamicsModel,
    q: Sequence[float] | np.ndarray,
    qd: Sequence[float] | np.ndarray,
    independent: Sequence[int | str],
    *,
    independent_speeds: Sequence[int | str] | None = None,
    t: float = 0.0,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> tuple[np.ndarray, np.ndarray]:
    """Complete a state on the constraints from the independent coordinates and speeds.

    The entries of ``q`` at ``independent`` and of ``qd`` at ``independent_speeds`` (default:
    ``independent``) are kept; the others are starting guesses.
    Dependent coordinates solve f(q, t) = 0 by Gauss–Newton (least squares on the dependent
    columns of A), dependent speeds solve A q̇ + b = 0: the projection of
    :mod:`pfaff.numeric.projection` (its iteration policy: it stops when the residual stops
    falling) in the Euclidean metric, with the independent coordinates held.

    Parameters
    ----------
    model : NumericModel
    q, qd : array_like, shape (n,)
    independent : sequence of str or int
        Coordinates (names or indices) whose values are given (n − m_holonomic of them).
    independent_speeds : sequence of str or int, optional
        Coordinates whose speeds are given (n − m of them), when they differ from
        ``independent``: a nonholonomic system (a rolling disk) has fewer independent speeds
        than coordinates. None: the speeds of ``independent``.
    t : float
    tol : float
        Target max |f| and max |A q̇ + b|.

    Returns
    -------
    q, qd : ndarray, shape (n,)

    Raises
    ------
    ConstraintError
        When the given independent values admit no consistent completion (the residual is named).

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> q, qd = consistent_state(model, [0.6, -1.0], [0.8, 0.0], ["x"])
    >>> np.round(q, 12).tolist(), np.round(qd, 12).tolist()
    ([0.6, -0.8], [0.8, 0.6])
    """
    check_model(model)
    names = model.coordinate_names if isinstance(model.coordinate_names, list) else None
    t, q, qd = check_state(t, q, qd, model.n, names, ("t", "q", "qd"))
    tol, max_iter = projection_options(tol, max_iter)
    ind = _indices(model, independent)
    ind_s = (
        ind
        if independent_speeds is None
        else _indices(model, independent_speeds, "independent_speeds")
    )
    dep = np.setdiff1d(np.arange(model.n), ind)
    dep_s = np.setdiff1d(np.arange(model.n), ind_s)
    hol = np.asarray(model.holonomic, dtype=bool)

    def held(A: np.ndarray, free: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        """The least-squares correction of the ``free`` entries (columns of A) for r."""
        Ad = A[:, free]

        def correct(r: np.ndarray) -> np.ndarray:
            out = np.zeros(model.n)
            if free.size and Ad.shape[0]:
                out[free] = np.linalg.lstsq(Ad, r, rcond=None)[0]
            return out

        return correct

    def linearize(q_: np.ndarray, qd_: np.ndarray) -> ArrayLinearization:
        f, g = model.residual(t, q_, qd_)
        A = _dense(model.constraint_matrix(t, q_))
        pos = held(A[hol], dep)
        return ArrayLinearization(
            np.where(hol, f, 0.0), g, np.sqrt((A * A).sum(axis=1)), tol,
            lambda r: pos(r[hol]), held(A, dep_s), lambda v: model.residual(t, q_, v)[1],
        )  # fmt: skip

    q, qd, _ = newton_projection(linearize, q, qd, max_iter=max_iter)
    f, g = model.residual(t, q, qd)
    worst = max(np.abs(np.where(hol, f, 0.0)).max(initial=0.0), np.abs(g).max(initial=0.0))
    if not np.isfinite(worst) or worst > max(tol, 1e-9):
        raise ConstraintError(
            f"no consistent state completes the given independent coordinates "
            f"{[model.coordinate_names[i] for i in ind]}"
            + (
                ""
                if independent_speeds is None
                else f" and speeds {[model.coordinate_names[i] for i in ind_s]}"
            )
            + f": residual {worst:.3g} remains (are they independent, and do their values "
            "admit a solution? A nonholonomic system takes its independent speeds apart: "
            "`independent_speeds`)"
        )
    return q, qd
