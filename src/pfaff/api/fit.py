"""``pfaff.fit``: parameters and initial values identified from measured motion.

Least squares by SciPy's ``least_squares`` (trust-region reflective, bounds allowed) on the
weighted residuals w·(y(t_i; θ) − y_measured), with the exact Jacobian from the forward
sensitivities of :func:`pfaff.sensitivities` (one run per evaluation gives both).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pfaff.api.observe import Observation
from pfaff.core.errors import OptionError, SimulationError, StateError
from pfaff.integrate.sensitivity import sensitivities
from pfaff.numeric.checks import check_model

HUGE = 1e150  # |measured| beyond this: the squared residuals overflow


@dataclass(repr=False)
class FitResult:
    """The outcome of :func:`pfaff.fit`.

    Attributes
    ----------
    estimates : dict of str to float
        The fitted values by name (parameters, ``"q0.<name>"``, ``"qd0.<name>"``).
    standard_errors : dict of str to float
        From the Jacobian J at the optimum: the square roots of the diagonal of
        s² (JᵀJ)⁻¹, s² = Σ r²/(N − P) (N residuals, P fitted values): the usual asymptotic
        errors for independent noise of equal variance (after the weights).
    residuals : ndarray, shape (n_t, n_obs)
        Fitted minus measured values (unweighted).
    status : str
        ``"success"`` or ``"failed"`` (the optimizer did not converge); ``message`` says why.
    message : str
    t : ndarray, shape (n_t,)
    measured, fitted : ndarray, shape (n_t, n_obs)
    observed : list of str
        The labels of the observed quantities.
    nfev : int
        Runs with sensitivities made by the optimizer.
    """

    estimates: dict[str, float]
    standard_errors: dict[str, float]
    residuals: np.ndarray
    status: str
    message: str
    t: np.ndarray
    measured: np.ndarray
    fitted: np.ndarray
    observed: list[str] = field(default_factory=list)
    nfev: int = 0

    def __repr__(self) -> str:
        values = ", ".join(
            f"{k} = {v:.6g} ± {self.standard_errors[k]:.2g}" for k, v in self.estimates.items()
        )
        return f"<pfaff.FitResult {self.status}: {values}>"

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary (no arrays but the residuals' RMS per observation)."""
        rms = np.sqrt(np.mean(self.residuals**2, axis=0)) if len(self.t) else []
        return {
            "estimates": dict(self.estimates),
            "standard_errors": dict(self.standard_errors),
            "residual_rms": {k: float(v) for k, v in zip(self.observed, rms, strict=True)},
            "status": self.status,
            "message": self.message,
            "nfev": self.nfev,
        }

    def plot(self, path: str | Path | None = None) -> Any:
        """Measured points and the fitted motion, one panel per observed quantity; written to
        ``path`` (atomically) when given. Returns the matplotlib figure."""
        import matplotlib

        if path is not None:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        from pfaff.core.files import atomic_path

        k = self.measured.shape[1]
        fig, axes = plt.subplots(k, 1, figsize=(7, 2.2 * k + 0.6), sharex=True, squeeze=False)
        for i, ax in enumerate(axes[:, 0]):
            ax.plot(self.t, self.measured[:, i], ".", ms=3, label="measured")
            ax.plot(self.t, self.fitted[:, i], "-", lw=1.2, label="fitted")
            ax.set_ylabel(self.observed[i])
        axes[0, 0].legend(loc="best", fontsize=8)
        axes[-1, 0].set_xlabel("t")
        text = ", ".join(
            f"{n} = {v:.6g} ± {self.standard_errors[n]:.2g}" for n, v in self.estimates.items()
        )
        fig.suptitle(text, fontsize=9)
        fig.tight_layout()
        if path is not None:
            with atomic_path(path) as tmp:
                fig.savefig(tmp, format=Path(path).suffix.lstrip(".") or "png")
            plt.close(fig)
        return fig


def _number(v: object, arg: str) -> float:
    if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Real):
        raise OptionError(f"{arg} must be a real number; got {v!r:.60}")
    x = float(v)
    if not math.isfinite(x):
        raise OptionError(f"{arg} must be finite; got {x}")
    return x


def _unknowns(model: Any, parameters: object) -> list[tuple[str, str, int, float]]:
    """(label, kind, index, guess) of every fitted value; kind "p", "q0" or "qd0"."""
    if not isinstance(parameters, Mapping) or not parameters:
        raise OptionError(
            "`parameters` must be a non-empty dict of name -> initial guess; got "
            f"{parameters!r:.60}"
        )
    names, coords = list(model.parameters), list(model.coordinate_names)
    out = []
    for key, guess in parameters.items():
        if not isinstance(key, str):
            raise OptionError(f"`parameters` keys must be names; got {key!r:.60}")
        value = _number(guess, f"`parameters[{key!r}]`")
        kind, _, coord = key.partition(".")
        if key in names:
            out.append((key, "p", names.index(key), value))
        elif kind in ("q0", "qd0") and coord in coords:
            out.append((key, kind, coords.index(coord), value))
        else:
            raise OptionError(
                f"`parameters`: {key!r:.60} is neither a parameter of the model "
                f"({', '.join(names) or 'none'}) nor an initial value `q0.<coordinate>` or "
                f"`qd0.<coordinate>` (coordinates: {', '.join(coords)})"
            )
    return out


def _data(t: object, measured: object, n_obs: int) -> tuple[np.ndarray, np.ndarray]:
    try:
        ts = np.asarray(t, dtype=float)
        y = np.asarray(measured, dtype=float)
    except (TypeError, ValueError):
        raise OptionError("`t` and `measured` must be arrays of real numbers") from None
    if ts.ndim != 1 or len(ts) < 2 or not np.isfinite(ts).all() or np.any(np.diff(ts) <= 0):
        raise OptionError("`t` must be a finite, strictly increasing array of at least 2 times")
    if y.ndim == 1 and n_obs == 1:
        y = y[:, None]
    if y.shape != (len(ts), n_obs):
        raise OptionError(
            f"`measured` must have shape (len(t), len(observe)) = ({len(ts)}, {n_obs}); "
            f"got {y.shape}"
        )
    if not np.isfinite(y).all():
        raise OptionError("`measured` contains NaN or infinity")
    if np.abs(y).max(initial=0.0) > HUGE:  # the sum of squared residuals would overflow
        raise OptionError(
            f"`measured` has values beyond ±{HUGE:g} ({np.abs(y).max():.3g}): their squares "
            "overflow; measure in other units"
        )
    return ts, y


def _weights(weights: object, shape: tuple[int, int]) -> np.ndarray:
    if weights is None:
        return np.ones(shape)
    try:
        w = np.broadcast_to(np.asarray(weights, dtype=float), shape)
    except (TypeError, ValueError):
        raise OptionError(
            f"`weights` must be non-negative numbers of shape (n_obs,) or {shape}"
        ) from None
    if not np.isfinite(w).all() or (w < 0).any() or not w.any():
        raise OptionError("`weights` must be finite, non-negative and not all zero")
    return w


def _bounds(bounds: object, unknowns: list) -> tuple[np.ndarray, np.ndarray]:
    lo = np.full(len(unknowns), -np.inf)
    hi = np.full(len(unknowns), np.inf)
    if bounds is None:
        return lo, hi
    labels = [u[0] for u in unknowns]
    if not isinstance(bounds, Mapping):
        raise OptionError(f"`bounds` must be a dict of name -> (low, high); got {bounds!r:.60}")
    for key, pair in bounds.items():
        if key not in labels:
            raise OptionError(f"`bounds`: {key!r:.60} is not a fitted value ({', '.join(labels)})")
        if not isinstance(pair, Sequence) or len(pair) != 2:
            raise OptionError(f"`bounds[{key!r}]` must be (low, high); got {pair!r:.60}")
        i = labels.index(key)
        lo[i], hi[i] = (
            -np.inf if pair[0] is None else float(pair[0]),
            np.inf if pair[1] is None else float(pair[1]),
        )
        if not lo[i] < hi[i] or not lo[i] <= unknowns[i][3] <= hi[i]:
            raise OptionError(
                f"`bounds[{key!r}]` = ({lo[i]}, {hi[i]}) must be increasing and contain the "
                f"guess {unknowns[i][3]}"
            )
    return lo, hi


class _Problem:
    """Residuals and Jacobian of one fit, from one run with sensitivities per θ."""

    def __init__(
        self,
        model: Any,
        unknowns: list[tuple[str, str, int, float]],
        obs: Observation,
        ts: np.ndarray,
        y: np.ndarray,
        w: np.ndarray,
        q0: object,
        qd0: object,
        options: dict,
    ) -> None:
        self.model, self.unknowns, self.obs = model, unknowns, obs
        self.ts, self.y, self.w = ts, y, w
        self.q0, self.qd0, self.options = q0, qd0, options
        self.initial = any(u[1] != "p" for u in unknowns)
        for arg, kind in (("q0", q0), ("qd0", qd0)):
            if callable(kind) and any(u[1] == arg for u in unknowns):
                raise OptionError(
                    f"`{arg}` is a function of the parameters: its entries cannot be fitted"
                )
        self.pnames = [u[0] for u in unknowns if u[1] == "p"]
        self._last: tuple[bytes, np.ndarray, np.ndarray, np.ndarray] | None = None
        self.runs = 0

    def _start(self, theta: np.ndarray) -> tuple[object, object]:
        q0, qd0 = self.q0, self.qd0
        if not self.initial:
            return q0, qd0
        n = self.model.n
        q = np.array(q0, dtype=float).reshape(n)
        qd = np.array(qd0, dtype=float).reshape(n)
        for (_, kind, i, _), v in zip(self.unknowns, theta, strict=True):
            if kind == "q0":
                q[i] = v
            elif kind == "qd0":
                qd[i] = v
        return q, qd

    def evaluate(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(weighted residuals (N,), Jacobian (N, P), fitted values (n_t, n_obs)) at θ."""
        key = theta.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1:]
        vals = {u[0]: float(v) for u, v in zip(self.unknowns, theta, strict=True) if u[1] == "p"}
        model = self.model.with_parameters(vals) if vals else self.model
        q0, qd0 = self._start(theta)
        self.runs += 1
        run = sensitivities(
            model, q0, qd0, (self.ts[0], self.ts[-1]), self.pnames, self.initial,
            t_eval=self.ts, **self.options,
        )  # fmt: skip
        if run.status != "success" or len(run.t) != len(self.ts):
            raise SimulationError(
                f"the run at {self._describe(theta)} did not reach the last time: {run.message}"
            )
        labels = run.sensitivity_labels
        cols = [labels.index(u[0]) for u in self.unknowns]
        fixed = np.array([u[2] if u[1] == "p" else -1 for u in self.unknowns])
        fitted, dy = self.obs.values(run, cols, fixed)
        r = (self.w * (fitted - self.y)).ravel()
        J = (self.w[:, :, None] * dy).reshape(r.size, len(self.unknowns))
        self._last = (key, r, J, fitted)
        return r, J, fitted

    def _describe(self, theta: np.ndarray) -> str:
        return ", ".join(f"{u[0]} = {v:.6g}" for u, v in zip(self.unknowns, theta, strict=True))


def fit(
    model: Any,
    t: Sequence[float] | np.ndarray,
    measured: Sequence[Sequence[float]] | np.ndarray,
    parameters: Mapping[str, float],
    observe: Sequence[str | Any],
    q0: object,
    qd0: object,
    bounds: Mapping[str, tuple[float | None, float | None]] | None = None,
    weights: object = None,
    **options: Any,
) -> FitResult:
    """Fit parameters (and initial values) of a compiled model to measured motion.

    Parameters
    ----------
    model : NumericModel
        Its parameter values are the starting point of those not fitted.
    t : array_like, shape (n_t,)
        Measurement times (strictly increasing); the runs start at ``t[0]``.
    measured : array_like, shape (n_t, n_obs)
        Measured values, columns in the order of ``observe``.
    parameters : dict of str to float
        The fitted values and their initial guesses: parameter names, ``"q0.<coordinate>"`` or
        ``"qd0.<coordinate>"`` (an entry of the initial state).
    observe : list of str or sympy.Expr
        What ``measured`` holds: coordinate names, ``"<coordinate>_dot"`` for a rate, or SymPy
        expressions of the coordinates, their rates and the parameters (a point's position).
    q0, qd0 : array_like, shape (n,), or callable
        The initial state (entries named in ``parameters`` are replaced by the estimates), or
        functions of the parameter dict (:func:`pfaff.sensitivities`).
    bounds : dict of str to (low, high), optional
        Bounds of fitted values (None for no bound on a side).
    weights : array_like, shape (n_obs,) or (n_t, n_obs), optional
        Multiply the residuals (e.g. 1/σ of each channel).
    **options
        Options of :func:`pfaff.sensitivities` and :func:`pfaff.simulate` (``rtol``,
        ``independent``, ...).

    Returns
    -------
    FitResult

    Raises
    ------
    OptionError
        Unknown names, data of the wrong shape or not finite, bad weights or bounds.
    SimulationError
        A run at some trial values fails before the last measurement.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> truth = {"m": 1.0, "l": 0.8, "g": 9.81, "c": 0.05}
    >>> model = pfaff.models.damped_pendulum().equations().compile(truth)
    >>> t = np.linspace(0, 2, 21)
    >>> data = pfaff.simulate(model, [0.5], [0.0], (0, 2), t_eval=t).q
    >>> guess = model.with_parameters({"c": 0.1, "l": 1.0})
    >>> res = pfaff.fit(guess, t, data, {"c": 0.1, "l": 1.0}, ["theta"], [0.5], [0.0])
    >>> res.status, round(res.estimates["c"], 6), round(res.estimates["l"], 6)
    ('success', 0.05, 0.8)
    """
    from scipy.optimize import least_squares  # (imported on the first fit, not with pfaff)

    check_model(model)
    unknowns = _unknowns(model, parameters)
    coords = list(getattr(model.linearizer, "coordinates", ()) or ())
    obs = Observation(observe, coords, list(model.coordinate_names), list(model.parameters))
    ts, y = _data(t, measured, len(obs.labels))
    w = _weights(weights, y.shape)
    lo, hi = _bounds(bounds, unknowns)
    for key in ("t_eval", "t_span"):
        if key in options:
            raise OptionError(f"`{key}` is set by `t`: leave it out")
    problem = _Problem(model, unknowns, obs, ts, y, w, q0, qd0, options)
    x0 = np.array([u[3] for u in unknowns])
    try:
        sol = least_squares(
            lambda x: problem.evaluate(x)[0],
            x0,
            jac=lambda x: problem.evaluate(x)[1],
            bounds=(lo, hi),
            x_scale="jac",
            method="trf",
        )
    except StateError as e:
        raise SimulationError(f"a run of the fit could not start: {e}") from e
    r, J, fitted = problem.evaluate(sol.x)
    labels = [u[0] for u in unknowns]
    dof = r.size - len(unknowns)
    s2 = float(r @ r) / dof if dof > 0 else np.nan
    cov = s2 * np.linalg.pinv(J.T @ J)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return FitResult(
        estimates={k: float(v) for k, v in zip(labels, sol.x, strict=True)},
        standard_errors={k: float(v) for k, v in zip(labels, se, strict=True)},
        residuals=fitted - y,
        status="success" if sol.success else "failed",
        message=str(sol.message),
        t=ts,
        measured=y,
        fitted=fitted,
        observed=list(obs.labels),
        nfev=problem.runs,
    )
