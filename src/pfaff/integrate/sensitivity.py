"""``pfaff.sensitivities``: a run with the exact derivatives of its states by parameters and
initial values (forward sensitivities through the variational equations)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from pfaff.core.errors import ModelError, OptionError
from pfaff.derive.variational import VariationalKernel, variational_kernel
from pfaff.integrate.initial import _indices, consistent_state
from pfaff.integrate.sensstep import (
    AugmentedField,
    SensitivitySetup,
    stepper_for,
    tangent_project,
)
from pfaff.integrate.simulation import _span, simulate
from pfaff.numeric.checks import check_model, real_vector
from pfaff.numeric.redundant import independent_rows
from pfaff.numeric.structured import StructuredModel
from pfaff.numeric.value import single_threaded
from pfaff.results.sensitivity import SensitivityTrajectory
from pfaff.results.trajectory import Trajectory

FD_STEP = 1e-3  # relative step of the derivatives of a callable q0(p), qd0(p)


def _model_checked(model: Any) -> None:
    check_model(model)
    if isinstance(model, StructuredModel) or getattr(model, "linearizer", None) is None:
        raise ModelError(
            "sensitivities need a model compiled by EquationsOfMotion.compile; models with "
            "families of coordinates are not supported"
        )
    if getattr(model, "events", ()):
        raise OptionError(
            "sensitivities of runs with events are not supported (the sensitivities would "
            "need the saltation matrix at each event): the model has events "
            f"({', '.join(e.name for e in model.events)})"
        )


def _options_checked(options: dict) -> None:
    method = options.get("method", "projection")
    if method != "projection":
        raise OptionError(
            f"sensitivities integrate with method='projection' only; got `method`={method!r:.60}"
        )
    options.pop("method", None)
    if options.get("integrator", "DOP853") != "DOP853":
        raise OptionError(
            "sensitivities integrate with `integrator`='DOP853' only; got "
            f"{options['integrator']!r:.60}"
        )
    if options.get("events"):
        raise OptionError(
            "sensitivities of runs with events or impacts are not supported: pass no `events`"
        )
    if options.get("inputs"):
        raise OptionError("sensitivities of runs with `inputs` are not supported")


def parameter_indices(model: Any, parameters: object) -> list[int]:
    """Indices in the model's parameter order of the names ``parameters`` lists, each once."""
    names = list(model.parameters)
    if isinstance(parameters, str) or not isinstance(parameters, Sequence):
        raise OptionError(f"`parameters` must be a list of parameter names; got {parameters!r:.60}")
    out = []
    for p in parameters:
        if not isinstance(p, str) or p not in names:
            raise OptionError(
                f"`parameters`: {p!r:.60} is not a parameter of the model (parameters: "
                f"{', '.join(names) or 'none'})"
            )
        if names.index(p) in out:
            raise OptionError(f"`parameters` names `{p}` twice")
        out.append(names.index(p))
    return out


def _start(value: object, arg: str, model: Any, idx: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """(value at the model's parameters, its derivatives (n, n_p)): zero for an array; for a
    callable of the parameter dict, fourth-order central differences of step FD_STEP·max(1, |p|)."""
    n, names = model.n, list(model.coordinate_names)
    p0 = dict(model.parameters)
    if not callable(value):
        return real_vector(value, arg, n, names), np.zeros((n, len(idx)))
    fn: Callable[[dict], object] = value

    def at(p: dict) -> np.ndarray:
        return real_vector(fn(p), f"{arg}(p)", n, names)

    base = at(p0)
    D = np.zeros((n, len(idx)))
    keys = list(p0)
    for j, i in enumerate(idx):
        h = FD_STEP * max(1.0, abs(p0[keys[i]]))
        vals = [at({**p0, keys[i]: p0[keys[i]] + s * h}) for s in (-2, -1, 1, 2)]
        D[:, j] = (vals[0] - 8 * vals[1] + 8 * vals[2] - vals[3]) / (12 * h)
    return base, D


def _initial_columns(n: int, r: int, initial: bool) -> np.ndarray:
    """Seed (2n, r + 2n) with the unit vectors of the initial-value columns."""
    S = np.zeros((2 * n, r + 2 * n * initial))
    if initial:
        S[:, r:] = np.eye(2 * n)
    return S


def complete(
    kernel: VariationalKernel, x: np.ndarray, S: np.ndarray, ind: np.ndarray
) -> np.ndarray:
    """The derivatives of a state completed by :func:`pfaff.consistent_state` (the independent
    coordinates ``ind`` held): the rows of S at ``ind`` kept, the others solved from the
    linearized constraints (implicit function theorem), as consistent_state solves them."""
    n, r = kernel.n, kernel.n_p
    if not kernel.m:
        return S
    dep = np.setdiff1d(np.arange(n), ind)
    S = S.copy()
    Sq, Sv = S[:n], S[n:]
    Sq[dep], Sv[dep] = 0.0, 0.0
    A, V_q, V_p, f_p = kernel.tangent(x)
    hol = kernel.holonomic_rows
    if hol and dep.size:
        res = A[hol] @ Sq
        res[:, :r] += f_p
        Sq[dep] = -np.linalg.lstsq(A[hol][:, dep], res, rcond=None)[0]
    if dep.size:
        res = V_q @ Sq + A @ Sv
        res[:, :r] += V_p
        Sv[dep] = -np.linalg.lstsq(A[:, dep], res, rcond=None)[0]
    return S


def _state_x(field: AugmentedField, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    x = field.x.copy()
    n = len(q)
    x[0], x[1 : 1 + n], x[1 + n : 1 + 2 * n] = t, q, qd
    return x


def sensitivities(
    model: Any,
    q0: object,
    qd0: object,
    t_span: tuple[float, float],
    parameters: Sequence[str] = (),
    initial: bool = False,
    *,
    independent: Sequence[str | int] | None = None,
    **options: Any,
) -> SensitivityTrajectory:
    """Simulate and carry the derivatives of the state by parameters (and initial values).

    The variational equations (:mod:`pfaff.derive.variational`: ∂/∂q, ∂/∂q̇, ∂/∂p of M, h, Q,
    A, b, generated on the first call for these parameters through the model's linearizer
    factory; nothing at ``compile()``) are integrated with the state by the projection method:
    DOP853 on [q, q̇, S] with the step sizes chosen on the state alone (the sensitivities are
    left out of the error control), one LU factorization of the KKT matrix shared by q̈, λ and their derivatives. After every step the state is
    projected as by ``simulate(method="projection")`` and the sensitivities onto the tangent of
    the constraint manifold at the projected state: the smallest Euclidean correction giving
    f_q S_q + f_p = 0 (holonomic rows) and V_q S_q + A S_v + V_p = 0 (every row, V = A q̇ + b).

    Parameters
    ----------
    model : NumericModel
        From ``EquationsOfMotion.compile`` (families and models with events are refused).
    q0, qd0 : array_like, shape (n,), or callable
        The initial state, or functions of the dict of the model's parameter values returning
        it (a start that moves with the parameters, e.g. a configuration recompleted per wheel
        radius); their derivatives are taken by fourth-order central differences of relative
        step 1e-3 (truncation about 1e-12). A fixed start is not moved with the parameters;
        where a constraint moves with one, the start's sensitivity is the smallest correction
        onto the moved manifold.
    t_span : (float, float)
    parameters : sequence of str
        Names of the parameters differentiated by (columns in this order).
    initial : bool
        Also differentiate by every entry of q0 and q̇0 (columns ``"q0.<name>"``,
        ``"qd0.<name>"`` after the parameters). A constrained model needs ``independent``.
    independent : sequence of str or int, optional
        Complete (q0, q̇0) by :func:`pfaff.consistent_state` holding these coordinates; their
        derivatives then follow from the constraints (implicit function theorem), and the
        initial-value columns of the other coordinates are zero.
    **options
        Options of :func:`pfaff.simulate` (``method`` must be "projection"; no ``events``,
        no ``inputs``).

    Returns
    -------
    SensitivityTrajectory
        The run with ``sensitivity`` (k, 2n, n_s), ``sensitivity_labels`` and
        ``multiplier_sensitivity`` (k, m, n_s).

    Raises
    ------
    ModelError
        A model with families.
    OptionError
        An unknown or repeated parameter, another method, events, inputs, ``initial`` on a
        constrained model without ``independent``.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.pendulum().equations().compile({"L": 1.0, "g": 9.81, "m": 1.0})
    >>> run = pfaff.sensitivities(model, [0.01], [0.0], (0, 0.3), parameters=["g"], initial=True)
    >>> run.sensitivity_labels
    ['g', 'q0.theta', 'qd0.theta']
    >>> w = np.sqrt(9.81)  # small swings: θ(t) = θ0 cos(√g t)
    >>> dg, dq0 = run.sensitivity[-1, 0, :2]
    >>> bool(np.isclose(dq0, np.cos(0.3 * w), rtol=1e-4))
    True
    >>> bool(np.isclose(dg, -0.01 * 0.3 * np.sin(0.3 * w) / (2 * w), rtol=1e-3))
    True
    """
    _model_checked(model)
    _options_checked(options)
    with single_threaded():  # (tiny LAPACK calls: threads cost more than they give)
        return _sensitivities(model, q0, qd0, t_span, parameters, initial, independent, options)


def _sensitivities(
    model: Any,
    q0: object,
    qd0: object,
    t_span: tuple[float, float],
    parameters: Sequence[str],
    initial: bool,
    independent: Sequence[str | int] | None,
    options: dict,
) -> SensitivityTrajectory:
    """:func:`sensitivities` once the model and options are checked."""
    if not isinstance(initial, bool):
        raise OptionError(f"`initial` must be True or False; got {initial!r:.60}")
    idx = parameter_indices(model, parameters)
    n, m, r = model.n, model.m, len(idx)
    t0 = _span(t_span)[0]
    q, Dq = _start(q0, "q0", model, idx)
    qd, Dv = _start(qd0, "qd0", model, idx)
    S0 = _initial_columns(n, r, initial)
    S0[:n, :r], S0[n:, :r] = Dq, Dv
    kernel = variational_kernel(model.linearizer, tuple(idx))
    p = np.array(list(model.parameters.values()), dtype=float)
    probe = AugmentedField(SensitivitySetup(kernel, S0, np.arange(m), False, t0), p)
    if independent is not None:
        q, qd = consistent_state(model, q, qd, independent, t=t0)
        ind = _indices(model, independent)
        S0 = complete(kernel, _state_x(probe, t0, q, qd), S0, ind)
    elif initial and m:
        raise OptionError(
            "`initial`=True on a constrained model needs `independent` (the coordinates whose "
            "initial values are free; the others follow from the constraints)"
        )
    A = kernel.tangent(_state_x(probe, t0, q, qd))[0] if m else np.zeros((0, n))
    rows = independent_rows(A) if m else None
    keep = np.arange(m) if rows is None else np.asarray(rows)
    setup = SensitivitySetup(kernel, S0, keep, options.get("t_eval") is None, t0)
    traj = simulate(model, q, qd, t_span, method=stepper_for(setup), **options)
    return _report(traj, setup, p, initial, [list(model.parameters)[i] for i in idx], rows)


def _report(
    traj: Trajectory,
    setup: SensitivitySetup,
    p: np.ndarray,
    initial: bool,
    pnames: list[str],
    rows: np.ndarray | None,
) -> SensitivityTrajectory:
    """The trajectory with the recorded sensitivities, projected at its reported states, and
    the multipliers' sensitivities solved there."""
    n, m, k = setup.kernel.n, setup.kernel.m, setup.S0.shape[1]
    field = AugmentedField(setup, p)
    S = np.empty((len(traj.t), 2 * n, k))
    S_lam = np.empty((len(traj.t), m, k))
    for i, t in enumerate(traj.t):
        q, qd = traj.q[i], traj.qd[i]
        Si = tangent_project(setup.kernel, _state_x(field, t, q, qd), setup.records[float(t)])
        S[i] = Si
        S_lam[i] = field.solve(float(t), np.concatenate((q, qd, Si.ravel())))[2]
    names = list(traj.coordinate_names)
    labels = pnames + ([f"q0.{c}" for c in names] + [f"qd0.{c}" for c in names]) * initial
    return SensitivityTrajectory.of(
        traj,
        sensitivity=S,
        sensitivity_labels=labels,
        multiplier_sensitivity=S_lam if rows is None else None,
    )
