"""``pfaff.simulate``: integrate a compiled model with the constraint drift under control.

The driver checks the input, makes the initial state consistent (or refuses it), runs one of the
methods step by step (progress bar, Ctrl-C), records projected states, and post-processes them
into a :class:`pfaff.Trajectory` (q̈, λ, energies and residuals evaluated at every reported state).
"""

from __future__ import annotations

import inspect
import math
import numbers
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import fields

import numpy as np

from pfaff.core.errors import (
    ConstraintError,
    OptionError,
    PfaffError,
    SimulationError,
    StateError,
    raised_in_generated_code,
    undefined_at,
)
from pfaff.core.events import Event, EventRecord
from pfaff.core.keywords import checked_keywords
from pfaff.integrate.contact import ContactRun, Layout, run_segments
from pfaff.integrate.events import SINGULAR, AttitudeEvents, UserEvents
from pfaff.integrate.ida import IDAStepper
from pfaff.integrate.inputs import DrivenModel
from pfaff.integrate.integrators import RK_METHODS, BaumgarteRK, ProjectedRK
from pfaff.integrate.loop import compiled_loop
from pfaff.integrate.output import output_kind, streamed
from pfaff.integrate.pace import Pace, state_bytes
from pfaff.integrate.scale import DEFAULT_TOL, constraint_scale
from pfaff.integrate.stepper import Stepper, StepperOptions, _RunFailure
from pfaff.numeric.checks import check_model, check_state
from pfaff.numeric.projection import Projector
from pfaff.numeric.protocol import DynamicsModel
from pfaff.numeric.value import single_threaded
from pfaff.results.trajectory import Trajectory

METHODS: dict[str, type[Stepper]] = {
    cls.name: cls for cls in (ProjectedRK, BaumgarteRK, IDAStepper)
}  # the built-in methods by name; simulate(method=...) also takes any Stepper subclass


def _real(v: object, key: str) -> float:
    """An option's value as a float: a real number (not a string, a bool or a complex)."""
    if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Real):
        raise OptionError(f"`{key}` must be a real number; got {v!r:.80}")
    x = float(v)
    if math.isnan(x):
        raise OptionError(f"`{key}` is NaN")
    return x


def _span(t_span: object) -> tuple[float, float]:
    if isinstance(t_span, str | bytes | dict) or not hasattr(t_span, "__iter__"):
        raise OptionError(f"`t_span` must be two numbers (t0, t_end); got {t_span!r:.80}")
    vals = list(t_span)  # type: ignore[call-overload]
    if len(vals) != 2:
        raise OptionError(f"`t_span` must be two numbers (t0, t_end); got {t_span!r:.80}")
    t0, t1 = (_real(v, "t_span") for v in vals)
    if not (math.isfinite(t0) and math.isfinite(t1)):
        raise OptionError(f"`t_span` must be finite; got ({t0}, {t1})")
    if t1 <= t0:
        kind = "empty" if t1 == t0 else "reversed"
        raise OptionError(f"`t_span` is {kind}: t_end = {t1:g} must be greater than t0 = {t0:g}")
    return t0, t1


def _t_eval(t_eval: object, t0: float, t1: float) -> np.ndarray | None:
    if t_eval is None:
        return None
    try:
        raw = np.asarray(t_eval)
        if raw.dtype.kind not in "iufO":  # complex, strings, booleans: not times
            raise TypeError
        te = np.asarray(raw, dtype=float).ravel()
    except (TypeError, ValueError):
        raise OptionError(f"`t_eval` must be an array of real times; got {t_eval!r:.80}") from None
    if not np.isfinite(te).all():
        raise OptionError("`t_eval` contains NaN or infinity")
    if te.size == 0 or np.any(np.diff(te) <= 0):
        raise OptionError("`t_eval` must be non-empty and strictly increasing")
    if te[0] < t0 or te[-1] > t1:
        raise OptionError(f"`t_eval` must lie inside t_span [{t0:g}, {t1:g}]")
    return te


MAX_STEPS = 1e9  # a max_step that forces more steps than this is refused (it would not end)
LAZY_NAMES = 1 << 16  # longer name sequences stay the model's lazy ones in a trajectory


def _stepper_class(method: object) -> type[Stepper]:
    """The :class:`Stepper` subclass ``method`` names or is (an :class:`OptionError` otherwise)."""
    if isinstance(method, str) and method in METHODS:
        return METHODS[method]
    if not isinstance(method, type):
        raise OptionError(
            f"unknown method {method!r:.80}; `method` must be one of {', '.join(METHODS)} or a "
            "subclass of pfaff.Stepper"
        )
    if not issubclass(method, Stepper):
        raise OptionError(
            f"`method` must be one of {', '.join(METHODS)} or a subclass of pfaff.Stepper; got "
            f"the class {method.__qualname__:.80}, which is not one"
        )
    if inspect.isabstract(method):
        missing = ", ".join(sorted(method.__abstractmethods__))
        raise OptionError(
            f"`method` {method.__qualname__:.80} is abstract: it does not implement {missing}"
        )
    return method


def _options(kw: dict, span: tuple[float, float]) -> dict:
    """Check every option of :func:`simulate` (an :class:`OptionError` naming it) before any work."""
    for key in ("rtol", "atol", "alpha", "beta", "constraint_tol", "initial_tol", "rest_speed"):
        if key == "constraint_tol" and kw[key] is None:  # scaled to the problem (integrate.scale)
            continue
        v = _real(kw[key], key)
        if not (math.isfinite(v) and v >= 0):
            raise OptionError(f"`{key}` must be a finite number >= 0; got {kw[key]!r}")
        kw[key] = v
    if (
        kw["rtol"] <= 0
        or kw["atol"] <= 0
        or (kw["constraint_tol"] is not None and kw["constraint_tol"] <= 0)
    ):
        raise OptionError("`rtol`, `atol` and `constraint_tol` must be positive")
    if kw["max_step"] is not None:  # SciPy's own checks would surface as bare ValueErrors
        v = _real(kw["max_step"], "max_step")
        if not v > 0:
            raise OptionError(f"`max_step` must be positive (or None: no limit); got {v:g}")
        kw["max_step"] = v if math.isfinite(v) else None  # +inf: no limit
        if math.isfinite(v) and (span[1] - span[0]) / v > MAX_STEPS:
            raise OptionError(
                f"`max_step` = {v:g} would take more than {MAX_STEPS:.0e} steps over t_span "
                f"(length {span[1] - span[0]:g}): choose a larger max_step or a shorter span"
            )
    if kw["first_step"] is not None:
        v, length = _real(kw["first_step"], "first_step"), span[1] - span[0]
        if not (0 < v <= length):
            raise OptionError(
                f"`first_step` must be positive and at most the length of t_span ({length:g}); "
                f"got {v:g}"
            )
        kw["first_step"] = v
    v = kw["max_seconds"]
    if v is not None:
        v = _real(v, "max_seconds")
        if not (v > 0 and math.isfinite(v)):
            raise OptionError(
                f"`max_seconds` must be a positive number of seconds or None (no limit); got {v:g}"
            )
        kw["max_seconds"] = v
    v = kw["max_steps"]
    if v is not None and (isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < 1):
        raise OptionError(
            f"`max_steps` must be a positive integer or None (no limit); got {v!r:.80}"
        )
    if not isinstance(kw["integrator"], str) or kw["integrator"] not in RK_METHODS:
        raise OptionError(
            f"`integrator` must be one of {', '.join(RK_METHODS)}; got {kw['integrator']!r:.80}"
        )
    if not (kw.get("ida_jacobian") is None or kw["ida_jacobian"] in ("fd", "approximate")):
        raise OptionError(
            f"`ida_jacobian` must be 'fd' or 'approximate'; got {kw['ida_jacobian']!r:.80}"
        )
    for key, optional in (
        ("project_initial", False),
        ("project_output", True),
        ("progress", True),
        ("throw", False),
    ):
        v = kw.pop(key) if key in ("project_output", "progress", "throw") else kw[key]
        if not (isinstance(v, bool | np.bool_) or (optional and v is None)):
            allowed = "True, False or None" if optional else "True or False"
            raise OptionError(f"`{key}` must be {allowed}; got {v!r:.80}")
    return kw


def initial_state(
    model: DynamicsModel, t0: float, q0: object, qd0: object, projector: Projector, opts: dict
) -> tuple[np.ndarray, np.ndarray]:
    """Check (q0, q̇0) against the constraints; polish it onto them, or refuse it with the residual.

    Then check that the accelerations are determined there (``check_determined``: M positive
    definite on the admissible motions, the constraints consistent), once per run.
    """
    names = model.coordinate_names if isinstance(model.coordinate_names, list) else None
    t0, q, qd = check_state(t0, q0, qd0, model.n, names, ("t0", "q0", "qd0"))
    if model.m:
        q, qd = _onto_constraints(model, t0, q, qd, projector, opts)
    lock = AttitudeEvents(model.attitudes).singular(q)
    if lock is not None:  # (M is singular there too: name the cause, not the symptom)
        raise StateError(f"the initial state is at a singular attitude: {lock}")
    model.check_determined(t0, q, qd)
    return q, qd


def _onto_constraints(
    model: DynamicsModel, t0: float, q: np.ndarray, qd: np.ndarray, projector: Projector, opts: dict
) -> tuple[np.ndarray, np.ndarray]:
    """The initial state polished onto the constraints, or refused with its residual."""
    f, g = model.residual(t0, q, qd)
    f = np.where(projector.holonomic, f, 0.0)
    worst = max(np.abs(f).max(), np.abs(g).max())
    if worst > opts["initial_tol"] and not opts["project_initial"]:
        i = int(np.argmax(np.maximum(np.abs(f), np.abs(g))))
        raise StateError(
            f"the initial state is off the constraint manifold: max |f| = {np.abs(f).max():.3g}, "
            f"max |A q̇ + b| = {np.abs(g).max():.3g} (worst: constraint "
            f"`{model.constraint_names[i]}`). Use pfaff.consistent_state to complete a state from "
            "independent coordinates, or pass project_initial=True to project it"
        )
    try:
        with np.errstate(all="ignore"):
            q, qd, _ = projector(t0, q, qd)
    except (ValueError, np.linalg.LinAlgError, FloatingPointError):  # NaN from a singular A
        q = qd = np.full(model.n, np.nan)
    if not (np.isfinite(q).all() and np.isfinite(qd).all()):
        raise StateError(
            "the initial state could not be projected onto the constraints: the constraint "
            "Jacobian is singular there (e.g. a pendulum bob at its pivot); start elsewhere"
        )
    if projector.residual(t0, q, qd) > max(opts["initial_tol"], 1e3 * projector.tol):
        raise StateError("the initial state could not be projected onto the constraints")
    return q, qd


@checked_keywords
def simulate(
    model: DynamicsModel,
    q0: Sequence[float] | np.ndarray,
    qd0: Sequence[float] | np.ndarray,
    t_span: tuple[float, float],
    *,
    method: str | type[Stepper] = "projection",
    rtol: float = 1e-9,
    atol: float = 1e-11,
    t_eval: Sequence[float] | np.ndarray | None = None,
    integrator: str = "DOP853",
    max_step: float | None = None,
    first_step: float | None = None,
    alpha: float = 10.0,
    beta: float = 10.0,
    constraint_tol: float | None = None,
    initial_tol: float = 1e-8,
    project_initial: bool = False,
    project_output: bool | None = None,
    ida_jacobian: str | None = None,
    progress: bool | None = None,
    throw: bool = False,
    inputs: dict | None = None,
    events: Sequence[Event] = (),
    rest_speed: float = 1e-6,
    max_steps: int | None = None,
    max_seconds: float | None = None,
    output: str | os.PathLike | None = None,
) -> Trajectory:
    """Simulate a compiled model from (q0, q̇0) over ``t_span``.

    Parameters
    ----------
    model : NumericModel
        From ``EquationsOfMotion.compile``.
    q0, qd0 : array_like, shape (n,)
        Initial coordinates and speeds (checked against the constraints).
    t_span : (float, float)
        Start and end time, end > start.
    method : {"projection", "baumgarte", "ida"} or Stepper subclass
        "projection" (default): adaptive Runge–Kutta on the acceleration-level equations, the state
        projected mass-orthogonally onto f = 0 and A q̇ + b = 0 after every step; passes
        configurations where A loses rank (see :mod:`pfaff.numeric.kkt`). "baumgarte": the stabilized
        field A q̈ + Ȧq̇ + ḃ = −2α(A q̇ + b) − β² f, no projection (through such configurations
        only with α, β fast against the motion). "ida": SUNDIALS IDA on the index-2 GGL
        formulation. A :class:`pfaff.Stepper` subclass (the class): a method of one's own.
    rtol, atol : float
        Integrator tolerances.
    t_eval : array_like, shape (k,), optional
        Report these times (interpolated, then projected); default: every step.
    integrator : {"DOP853", "RK45", "RK23"}
        Runge–Kutta method of "projection" and "baumgarte".
    max_step, first_step : float, optional
    alpha, beta : float
        Baumgarte gains (1/time); α = β damps the drift critically. Choose them a few times faster
        than the motion's own rates.
    constraint_tol : float, optional
        Target max |f| and max |A q̇ + b| of projected states. Default: 1e-12 times the scale
        of the holonomic constraints at the start, when below 1 (``‖∂f/∂q‖`` times the largest
        coordinate: a 1 mm pendulum gets 2e-18, so its length drifts no more than a metre
        pendulum's; :mod:`pfaff.integrate.scale`).
    initial_tol : float
        Largest initial residual polished away silently; beyond it the state is refused unless
        ``project_initial``.
    project_initial : bool
        Project an inconsistent initial state instead of raising.
    project_output : bool, optional
        Project reported states (default: yes, except for "baumgarte", whose drift is reported:
        a stepper's ``reports_drift``).
    ida_jacobian : {"fd", "approximate"}, optional
        IDA's Newton matrix: finite differences (default up to 80 unknowns) or assembled from M
        and A without curvature terms (default beyond).
    progress : bool, optional
        Progress bar on stderr for runs longer than a second; default: when stderr is a terminal.
    throw : bool
        Raise :class:`pfaff.errors.SimulationError` instead of returning a failed trajectory.
    inputs : dict, optional
        Values of the model's inputs (``System.add_input``) during the run, by name: a number,
        a function u(t), or a feedback law u(t, q, q̇) (:mod:`pfaff.integrate.inputs`).
    events : sequence of Event, optional
        Zero crossings of g(t, q, q̇) to find (:class:`pfaff.Event`), besides the model's own
        (``System.add_event``, ``model.events``). Each root is bracketed on the integrator's
        dense output to 1e-12·max(1, |t|), reported in :attr:`Trajectory.events` and added as a
        reported state; a terminal event ends the run there with status "success".
    rest_speed : float
        With unilateral constraints (``System.add_unilateral_constraint``): a contact closing
        at this speed or slower (gap units per second) closes without a bounce (an event of
        kind "rest"; see :mod:`pfaff.integrate.contact`).
    max_steps : int, optional
        Fail after this many steps (default: no limit). Whatever the span, a run fails on its
        own only when its steps collapse against its own history (chattering, e.g. Coulomb
        friction about q̇ = 0) or stop advancing t (:mod:`pfaff.integrate.pace`); without
        ``t_eval`` every step is recorded, and a run whose states would need more than 1 GiB
        (or half the available memory) warns (:class:`pfaff.LongRunWarning`).
    max_seconds : float, optional
        Fail after this many seconds of wall-clock time from the first step (default: no
        limit); the message starts "timed out at t = ...".
    output : str or path, optional
        A file the reported states go to. ``"run.nc"``: each state is appended to a netCDF
        file as it is reported (time the record dimension) and dropped from memory, so that
        the run holds one state whatever its length; the file is renamed into place when the
        run ends, also when it ends early (the states so far, the status in its attributes),
        and the returned trajectory reads its arrays from it (``traj.output``). ``"run.csv"``:
        the trajectory written as CSV at the end (refused over 65536 columns).
        :mod:`pfaff.integrate.output`.

    Returns
    -------
    Trajectory
        ``status`` is "success", "failed" (with the time and reason in ``message``) or
        "interrupted" (Ctrl-C; the part computed so far is kept).

    Raises
    ------
    SimulationError
        With ``throw=True``, when the run fails; without it, when the method fails before its
        first step.
    ModelTypeError
        ``model`` is not a compiled model (e.g. equations not yet ``.compile(parameters)``-d).
    OptionError
        An option out of range or of the wrong type (named).
    StateError
        ``q0`` or ``qd0`` not real, finite and of shape (n,); the initial state off the
        constraints (beyond ``initial_tol``); the equations not defined at it (an overflow).
    InertiaError
        Some acceleration is undetermined at the initial state (a coordinate without inertia
        that no constraint fixes), or M is not positive definite on the admissible motions.
    ConstraintError
        No acceleration satisfies the constraints at the initial state.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> traj = pfaff.simulate(model, [0.0, -1.0], [1.0, 0.0], (0, 2), t_eval=[0, 1, 2])
    >>> traj.q.shape, traj.status
    ((3, 2), 'success')
    """
    check_model(model)
    with single_threaded():  # the run's thread policy (pfaff.numeric.value), set once
        return _simulate(
            model, q0, qd0, t_span, t_eval, method, rtol, atol, alpha, beta, constraint_tol,
            integrator, max_step, first_step, initial_tol, project_initial, ida_jacobian,
            project_output, progress, throw, inputs, events, rest_speed, max_steps,
            max_seconds, output,
        )  # fmt: skip


def _events(model: DynamicsModel, events: object) -> UserEvents:
    """The model's events and the ``events`` argument, checked."""
    if isinstance(events, Event) or not isinstance(events, Sequence | tuple | list):
        raise OptionError(f"`events` must be a list of pfaff.Event; got {events!r:.80}")
    for i, ev in enumerate(events):
        if not isinstance(ev, Event):
            raise OptionError(
                f"`events[{i}]` must be a pfaff.Event(g, name, direction, terminal); got {ev!r:.80}"
            )
    return UserEvents([*getattr(model, "events", ()), *events])


def _simulate(
    model, q0, qd0, t_span, t_eval, method, rtol, atol, alpha, beta, constraint_tol,
    integrator, max_step, first_step, initial_tol, project_initial, ida_jacobian,
    project_output, progress, throw, inputs, events, rest_speed=1e-6, max_steps=None,
    max_seconds=None, output=None,
):  # fmt: skip
    """:func:`simulate` once its arguments are known: a run copy of the model, stepped."""
    model = model.for_run() if hasattr(model, "for_run") else model  # the user's model is kept
    user = _events(model, events)
    contacts = getattr(model, "contacts", None)  # unilateral constraints (integrate/contact)
    if inputs:
        model = DrivenModel(model, inputs)
    t0, t1 = _span(t_span)
    te = _t_eval(t_eval, t0, t1)
    cls = _stepper_class(method)
    opts = _options(
        dict(
            rtol=rtol,
            atol=atol,
            alpha=alpha,
            beta=beta,
            constraint_tol=constraint_tol,
            integrator=integrator,
            max_step=max_step,
            first_step=first_step,
            initial_tol=initial_tol,
            project_initial=project_initial,
            ida_jacobian=ida_jacobian,
            rest_speed=rest_speed,
            project_output=project_output,
            progress=progress,
            throw=throw,
            max_steps=max_steps,
            max_seconds=max_seconds,
        ),
        (t0, t1),
    )
    kind = output_kind(output, model.n, model.m)
    if kind == "nc" and contacts:
        raise OptionError(
            "`output`: a run with unilateral constraints is not streamed to a file yet; "
            "write its result with traj.to_netcdf(path)"
        )
    if opts["constraint_tol"] is None:
        try:  # (a bad state is refused by initial_state below, naming it)
            q_start, qd_start = (np.asarray(v).ravel() for v in (q0, qd0))
        except (TypeError, ValueError):
            q_start = qd_start = np.zeros(0)
        if not all(x.dtype.kind in "iuf" for x in (q_start, qd_start)):
            q_start = qd_start = np.zeros(0)
        ok = q_start.size == qd_start.size == model.n
        scale = constraint_scale(model, t0, q_start, qd_start) if ok else 1.0
        opts["constraint_tol"] = DEFAULT_TOL * scale
    projector = Projector(model, tol=opts["constraint_tol"])
    options = StepperOptions(**{f.name: opts[f.name] for f in fields(StepperOptions)})
    try:
        q0a, qd0a = initial_state(model, t0, q0, qd0, projector, opts)
        stepper = None if contacts else cls(model, t0, q0a, qd0a, t1, options, projector)
    except _RunFailure as e:  # the method could not start
        raise SimulationError(str(e)) from None
    except (ValueError, ArithmeticError) as e:  # the user's equations, not defined at t0
        if isinstance(e, PfaffError) or not raised_in_generated_code(e):
            raise
        raise undefined_at(e, t0) from None
    if project_output is None:
        project_output = not cls.reports_drift
    memory = state_bytes(model.n, model.m) if te is None and kind != "nc" else None
    pace = Pace(t1, max_steps, memory, opts["max_seconds"])
    if contacts:
        run = ContactRun(model, contacts, inputs, opts["rest_speed"], opts["constraint_tol"])
        found = _run_contacts(run, cls, options, te, t0, t1, q0a, qd0a, progress, user,
                              project_output, pace)  # fmt: skip
        status, message, segs, stats, projectors = found
        if status != "success" and throw:
            raise SimulationError(message)
        for p in projectors:
            for key, v in p.stats.items():
                stats[key] = stats.get(key, 0) + v
        layout = Layout(model, segs)
        return _trajectory(
            layout, cls.name, segs, status, message, stats, projector, project_output
        )
    power = model.power_function() if model.applied_power else None
    run = _Run(stepper, projector if project_output else None, te, t0, t1, progress, power)
    run.pace = pace
    run.events = AttitudeEvents(model.attitudes)
    run.user = user
    run.restart = lambda t, q, qd: cls(model, t, q, qd, t1, options, projector)
    try:
        run.loop, why = compiled_loop(run, model)  # (integrate/loop: where it applies)
    except KeyboardInterrupt:  # while numba loaded: the run ends at once, "interrupted"
        run.loop, why, run.interrupted_early = None, "interrupted while loading", True
    if kind == "nc":
        return streamed(run, model, output, cls.name, projector, project_output, (q0a, qd0a),
                        throw)  # fmt: skip
    status, message = run.go(q0a, qd0a)
    if status != "success" and throw:
        raise SimulationError(message)
    stats = {"stepping": "python", **run.finish(), **projector.stats, "cpu_time": run.cpu}
    if why:
        stats["stepping_reason"] = why
    traj = _trajectory(model, cls.name, run, status, message, stats, projector, project_output)
    if kind == "csv":
        traj.to_csv(output)
    return traj


def _run_contacts(
    contacts, cls, options, te, t0, t1, q0, qd0, progress, user, project_output, pace
):  # fmt: skip
    """A run with unilateral constraints: one :class:`_Run` per segment between contact
    events (:func:`pfaff.integrate.contact.run_segments`); one :class:`Pace` counts their steps."""

    def segment(model, t, q, qd, events):
        projector = Projector(model, tol=contacts.tol)
        stepper = cls(model, t, q, qd, t1, options, projector)
        tes = te if te is None or t == t0 else te[te > t]
        power = model.power_function() if model.applied_power else None
        run = _Run(stepper, projector if project_output else None, tes, t, t1, progress, power)
        run.events, run.user, run.pace = AttitudeEvents(model.attitudes), events, pace
        pace.restart()  # each segment its own history; max_steps over them all
        run.restart = lambda t_, q_, qd_: cls(model, t_, q_, qd_, t1, options, projector)
        status, message = run.go(q, qd)
        return run, status, message, projector

    return run_segments(contacts, t0, q0, qd0, t1, user, segment)


class _Run:
    """The stepping loop: records states, drives the progress bar, catches Ctrl-C and failures."""

    def __init__(
        self, stepper: Stepper, projector, te, t0: float, t1: float, progress, power=None
    ) -> None:
        self.stepper, self.projector, self.te = stepper, projector, te
        self.project_steps = not stepper.projects_steps
        self.t0, self.t1 = t0, t1
        self.progress = sys.stderr.isatty() if progress is None else bool(progress)
        self.power = power  # P(t, q, q̇) of the applied forces, or None when they do no work
        self.T: list[float] = []
        self.Q: list[np.ndarray] = []
        self.QD: list[np.ndarray] = []
        self.W: list[float] = []  # work of the applied forces from t0 to each recorded time
        self.cpu = 0.0
        self.events = AttitudeEvents(())  # MRP switching, Euler singularity (set by simulate)
        self.restart = None  # (t, q, q̇) -> a new stepper, after a switch
        self.switches: list[tuple[float, str]] = []
        self.user = UserEvents(())  # the user's events (simulate(events=...), model.events)
        self.records: list[EventRecord] = []  # the events found, in time order
        self._done: list[dict] = []  # the statistics of steppers replaced after a switch
        self._last_q: np.ndarray | None = None  # the state of the last event check
        self.pace = Pace(t1, None, None)  # the stall test and the step limit (set by simulate)
        self.sink = None  # the file the states go to as they are recorded (integrate/output)
        self.loop = None  # the compiled loop, where it applies (set by simulate)
        self.interrupted_early = False  # Ctrl-C before the first step (the run ends there)

    def finish(self) -> dict:
        """The steppers' statistics, summed over restarts."""
        stats = dict(self.stepper.finish())
        for old in self._done:
            for key, v in old.items():
                if isinstance(v, int | float) and isinstance(stats.get(key), int | float):
                    stats[key] += v
        if self._done:
            stats["restarts"] = len(self._done)
        return stats

    def _event(self, st: Stepper) -> tuple[np.ndarray, np.ndarray] | None:
        """After an accepted step: stop at an Euler singularity; switch MRPs (and restart)."""
        q, qd = st.state()
        message = self.events.singular(q, before=self._last_q)
        self._last_q = q
        if message is not None:
            raise _Singular(message)
        q2, qd2, names = self.events.switch(q, qd)
        if not names:
            return None
        self.switches += [(float(st.t), name) for name in names]
        self._done.append(dict(st.finish()))
        self.stepper = self.restart(st.t, q2, qd2)
        return q2, qd2

    def _record(self, t: float, q: np.ndarray, qd: np.ndarray, project: bool, w: float) -> None:
        if project and self.projector is not None:
            q, qd, _ = self.projector(t, q, qd)
        if self.events.mrps:  # a dense-output point past |σ| = 1, before the step's switch
            q, qd, _ = self.events.switch(q, qd)
        self.T.append(t)
        self.Q.append(np.array(q))
        self.QD.append(np.array(qd))
        self.W.append(w)
        if self.sink is not None:
            self.sink.take(self.T, self.Q, self.QD, self.W, keep=bool(self.user))

    def _trim(self) -> None:
        """The recorded states cut to one length (an interrupt between two appends)."""
        k = min(len(self.T), len(self.Q), len(self.QD), len(self.W))
        for rows in (self.T, self.Q, self.QD, self.W):
            del rows[k:]

    def _dense_report(self, st: Stepper, points: list, work: float) -> None:
        """Record the states at ``points`` (t, event index or None) inside the last step, in
        time order, from its dense output; an event's state also goes to :attr:`records`."""
        if not points:
            return
        states = st.dense(np.array([p[0] for p in points]))
        for (ti, i), (q, qd) in zip(points, states, strict=True):
            if not (self.T and self.T[-1] == ti):  # no second state at one time
                self._record(ti, q, qd, True, work + self._work(ti))
            if i is not None:
                name = self.user.names[i]
                self.records.append(EventRecord(name, ti, self.Q[-1].copy(), self.QD[-1].copy()))

    def _stopped(self, root: tuple[float, int]) -> tuple[str, str]:
        t, i = root
        ev = self.user.events[i]
        nth = f" (occurrence {ev.terminal})" if ev.terminal > 1 else ""
        return (
            "success",
            f"stopped by the terminal event `{self.user.names[i]}`{nth} at t = {t:.17g}",
        )

    def _work(self, b: float | None = None) -> float:
        """∫ P dt from the start of the last step to ``b`` (its end when None): the stepper's own
        quadrature over a whole step, its dense output up to a time inside it
        (:mod:`pfaff.integrate.work`)."""
        if self.power is None:
            return 0.0
        if b is None:
            return self.stepper.step_work(self.power)
        return self.stepper.work_until(self.power, b)

    def _bar(self):
        if not self.progress:
            return None
        from tqdm import tqdm

        return tqdm(
            total=self.t1 - self.t0, delay=1.0, unit="s", unit_scale=True, file=sys.stderr,
            desc="simulating", bar_format="{desc}: {percentage:3.0f}%|{bar}| t={n:.4g}/{total:.4g} [{elapsed}<{remaining}]",
        )  # fmt: skip

    def go(self, q0: np.ndarray, qd0: np.ndarray) -> tuple[str, str]:
        st, te = self.stepper, self.te
        k = 0  # next t_eval index
        if te is None or (te.size and te[0] == self.t0):
            self._record(self.t0, q0, qd0, False, 0.0)
            k = 1 if te is not None else 0
        bar = self._bar()
        start = time.process_time()
        status, message = "success", "reached the end of the time span"
        work = 0.0  # of the applied forces, up to the start of the current step
        try:
            if self.interrupted_early:
                raise KeyboardInterrupt
            events, user = bool(self.events), self.user
            if user:
                user.start(self.t0, q0, qd0)
            while st.t < self.t1:
                self.pace.limit()
                t_prev = st.t
                try:
                    moved = self.loop.advance(self, k, work) if self.loop else None
                    if moved is not None:  # the compiled loop's steps, their states recorded
                        k, work = moved
                        if bar is not None:
                            bar.update(st.t - t_prev)
                        continue
                    st.step()
                    self.pace.step(t_prev, st.t)
                    roots, stop = user.find(st, t_prev) if user else ([], False)
                    if te is None:
                        step_work = self._work()
                        self._dense_report(st, [(t, i) for t, i in roots], work)
                        if stop:
                            status, message = self._stopped(roots[-1])
                            break
                        done = st
                        switched = self._event(st) if events else None
                        state = done.state() if switched is None else switched
                        if not (roots and roots[-1][0] == done.t):  # (a root at the step's end)
                            self._record(done.t, *state, self.project_steps, work + step_work)
                    else:
                        end = roots[-1][0] if stop else st.t
                        j = int(np.searchsorted(te, end, side="right"))
                        points = [(float(ti), None) for ti in te[k:j]] + list(roots)
                        self._dense_report(st, sorted(points, key=lambda p: p[0]), work)
                        k = max(j, k)
                        if stop:
                            status, message = self._stopped(roots[-1])
                            break
                        step_work = self._work()
                        switched = self._event(st) if events else None
                    if user and switched is not None:
                        user.start(st.t, *switched)
                except Exception as e:
                    failure = _failure(e, st.t)
                    if failure is e:
                        raise
                    raise failure from e
                work += step_work
                st = self.stepper
                if bar is not None:
                    bar.update(st.t - t_prev)
        except KeyboardInterrupt:
            status, message = "interrupted", f"interrupted by the user at t = {st.t:.17g}"
            self._trim()
        except _RunFailure as e:
            status, message = "failed", f"{e.verb} at t = {st.t:.17g}: {e}"
            hint = e.hint and self.events
            near = self.events.singular(st.state()[0], 10 * SINGULAR) if hint else None
            if near is not None:  # the integrator gave up just before the check would stop it
                message += f" ({near})"
        finally:
            self.cpu = time.process_time() - start
            if bar is not None:
                bar.close()
        return status, message


class _Singular(_RunFailure):
    """An attitude set reached its singularity: the run stops (status "failed")."""

    verb = "stopped"

    def __init__(self, message: str) -> None:
        super().__init__(message, hint=False)


# the numerical failures of the equations at a state reached by a run: non-finite values
# (StateError, FloatingPointError), no acceleration satisfying the constraints (ConstraintError,
# a singular KKT system); a ValueError or ArithmeticError only when raised in generated code
NUMERICAL_FAILURES = (StateError, ConstraintError, FloatingPointError, np.linalg.LinAlgError)


def _failure(e: Exception, t: float) -> Exception:
    """What an exception raised while stepping at time ``t`` becomes: a :class:`_RunFailure`
    for a failure of the run (the stepper's own, or a numerical one of the equations), ``e``
    itself for anything else (a bug, a bad option found late: raised out of ``simulate``)."""
    if isinstance(e, _RunFailure):
        return e
    if isinstance(e, NUMERICAL_FAILURES):
        return _RunFailure(str(e))
    if (
        isinstance(e, ValueError | ArithmeticError)
        and not isinstance(e, PfaffError)
        and raised_in_generated_code(e)
    ):  # a math domain error, overflow or division by zero in the user's equations
        return _RunFailure(str(undefined_at(e, t)), hint=False)
    return e


def _stacked(rows: list, n: int) -> np.ndarray:
    """The recorded states as one (k, n) array; the list is emptied (no second copy alive)."""
    out = np.stack(rows) if rows else np.zeros((0, n))
    rows.clear()
    return out


def _names(names) -> list | object:
    """A model's names as the trajectory keeps them: a list, or the model's own (immutable,
    lazy) sequence when long (listing the ring's 2^21 names took 3 s of a 1 s run at N = 2^20;
    a run streamed to a file keeps them lazy too)."""
    return names if len(names) > LAZY_NAMES else list(names)


def _trajectory(model, method, run, status, message, stats, projector, project_output):
    n, m = model.n, model.m
    T = np.array(run.T)
    Q, QD = _stacked(run.Q, n), _stacked(run.QD, n)
    ev = model.evaluate_states(T, Q, QD) if len(T) else None
    if ev is None:
        z, zm = np.zeros((0, n)), np.zeros((0, m))
        ev = {"qdd": z, "multipliers": zm, "f": zm, "g": zm, "T": T, "V": T, "T0": T, "T2": T}
    res = ev.get("residual")  # a model may give f and g as views of one (k, 2, m) array
    if res is None:
        res = np.empty((len(T), 2, m))  # filled in place: no np.where / np.stack copies
        res[:, 0], res[:, 1] = ev.pop("f"), ev.pop("g")
    res[:, 0, ~np.asarray(model.holonomic, dtype=bool)] = 0.0
    return Trajectory(
        t=T,
        q=Q,
        qd=QD,
        qdd=ev["qdd"],
        multipliers=ev["multipliers"],
        kinetic=ev["T"],
        potential=ev["V"],
        jacobi=ev["T2"] - ev["T0"] + ev["V"],
        nc_work=np.array(run.W),
        constraint_residual=res,
        stats=stats,
        status=status,
        message=message,
        method=method,
        coordinate_names=_names(model.coordinate_names),
        multiplier_names=_names(model.multiplier_names),
        parameters=dict(model.parameters),
        projector=projector if project_output else None,
        switches=list(run.switches),
        events=list(run.records),
        geometry=model.geometry,  # what Trajectory.animate draws
        redundant_rows=ev.get("redundant_rows", np.zeros(len(T), dtype=np.int64)),
        impact_work=np.array(getattr(run, "IW", np.zeros(len(T)))),
        contact_open=ev.get("open", np.zeros((len(T), m), dtype=bool)),
    )
