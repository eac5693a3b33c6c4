"""A run with unilateral constraints: segments of smooth motion joined by impacts and releases.

Between events the run steps the model in which the closed contacts are holonomic rows
(``model.contacts.variant(mask)``, :mod:`pfaff.derive.contacts`) with the chosen method, from a
fresh stepper (IDA with a recomputed consistent state; Baumgarte stabilizes the closed rows, as
they are rows of that model). Each segment ends at the first root, on the stepper's dense output,
of a terminal event of the contacts (besides the user's events):

- an open contact: its gap falling through 0. Right after it opened (gap 0 at t_s) the event is
  the divided difference gap(t)/(t − t_s), whose limit at t_s is the opening rate ġ: a bounce
  too short for one step is still seen, and the impacts of a ball accumulating at t∞ (Zeno)
  each end a segment until their closing speed falls to ``rest_speed``;
- a closed contact: its multiplier λ falling through 0 (a release).

At the root, :meth:`ContactRun.transition` applies the impulse of the contacts touching there
(:func:`pfaff.integrate.impact.impulse`, Newton's law with restitution e, or 0 for a closing
speed at or below ``rest_speed``), closes the contacts that do not separate, opens those whose
multiplier would pull (the most negative first), projects the state onto the new model's
constraints and records the events ("impact", "rest", "release") and the impact work.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import ConstraintError, SimulationError, StateError
from pfaff.core.events import Event, EventRecord
from pfaff.integrate.events import UserEvents, root_tolerance
from pfaff.integrate.impact import MAX_CONTACTS, impulse
from pfaff.integrate.inputs import DrivenModel
from pfaff.integrate.stepper import _RunFailure
from pfaff.numeric.projection import Projector

# the numerical failures of the equations at an event's state (as in a step: a failed run)
NUMERICAL = (StateError, ConstraintError, FloatingPointError, np.linalg.LinAlgError)
MAX_REPEATS = 1000  # events in a row without time advancing: the run fails (no progress)


class ContactRun:
    """The modes of a run with contacts (see the module docstring).

    Parameters
    ----------
    model : DynamicsModel
        The run's model (no contact closed).
    contacts : CompiledContacts
        Its ``contacts`` (:mod:`pfaff.derive.contacts`).
    inputs : dict or None
        The run's inputs (each mode's model is driven by them).
    rest_speed : float
        Closing speeds at or below it close a contact without a bounce.
    tol : float
        The projection's ``constraint_tol``.
    """

    def __init__(
        self, model: Any, contacts: Any, inputs: dict | None, rest_speed: float, tol: float
    ) -> None:
        self.base, self.contacts, self.inputs = model, contacts, inputs
        self.k, self.mb = len(contacts), model.m
        self.e = np.array(self.contacts.restitution)
        self.rest_speed, self.tol = rest_speed, tol
        self._models: dict[tuple[bool, ...], Any] = {}
        self.touch = max(1e3 * tol, 1e-10)  # a gap this small touches
        self.impact_work = 0.0

    def model(self, mask: tuple[bool, ...]) -> Any:
        """The run's model with the contacts of ``mask`` closed (made once per run)."""
        m = self._models.get(mask)
        if m is None:
            if not any(mask):
                m = self.base
            else:
                m = self.contacts.variant(mask).for_run()
                if self.inputs:
                    m = DrivenModel(m, self.inputs)
            self._models[mask] = m
        return m

    # ------------------------------------------------------------------ gaps and forces
    def gaps(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The gaps (k,) and their rates ġ = a q̇ + b (k,) at a state."""
        g, A, b = self.contacts.gaps(t, q)
        return g, A @ qd + b

    def events(self, mask: tuple[bool, ...], t0: float, q0: np.ndarray) -> list[Event]:
        """The terminal events of the mode ``mask`` entered at (t0, q0): gaps of open contacts
        falling through 0 (divided by t − t0 where the gap starts at 0), multipliers of closed
        ones falling through 0."""
        gap0 = self.gaps(t0, q0, np.zeros_like(q0))[0]
        model, out, row = self.model(mask), [], self.mb
        for j, closed in enumerate(mask):
            name = self.contacts.names[j]
            if closed:
                out.append(Event(_multiplier(model, row), name, -1, True))
                row += 1
            else:
                fresh = abs(gap0[j]) <= self.touch
                out.append(Event(_gap(self, j, t0 if fresh else None), name, -1, True))
        return out

    def check_gaps(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """Refuse an initial state that penetrates a contact."""
        gap = self.gaps(t, q, qd)[0]
        bad = np.flatnonzero(gap < -self.touch)
        if bad.size:
            j = int(bad[0])
            raise StateError(
                f"the initial state penetrates the unilateral constraint "
                f"`{self.contacts.names[j]}`: its gap is {gap[j]:.3g} < 0"
            )

    # ------------------------------------------------------------------ events
    def transition(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        mask: tuple[bool, ...],
        released: int | None = None,
    ) -> tuple[tuple[bool, ...], np.ndarray, np.ndarray, list[tuple[str, str]]]:
        """The mode after an event at (t, q, q̇⁻) in mode ``mask``: the impulse of the contacts
        touching there, the contacts then closed (``released``: the one whose multiplier crossed
        zero opens), the state projected onto them, and the events as (name, kind)."""
        gap, rate = self.gaps(t, q, qd)
        J = [j for j in range(self.k) if (mask[j] or gap[j] <= self.touch) and j != released]
        kinds: list[tuple[str, str]] = []
        qd_plus = qd
        zero = 1e-9 * (1.0 + float(np.abs(qd).max(initial=0.0)))
        if any(rate[j] < 0.0 for j in J):
            qd_plus, kinds = self._impact(t, q, qd, J, rate)
            # events: the contacts that were open, and closed ones hit at a real speed
            kinds = [(self.contacts.names[j], kind) for j, kind in kinds
                     if not mask[j] or -rate[j] > zero]  # fmt: skip
            rate = self.gaps(t, q, qd_plus)[1]
        closed = [j for j in J if rate[j] <= zero]
        closed, q2, qd2 = self._settle(t, q, qd_plus, closed)
        new = tuple(j in closed for j in range(self.k))
        # released: by its multiplier, by the impulse of another contact, or pulling here
        kinds += [(self.contacts.names[j], "release") for j in range(self.k) if mask[j] > new[j]]
        return new, q2, qd2, kinds

    def _impact(
        self, t: float, q: np.ndarray, qd: np.ndarray, J: list[int], rate: np.ndarray
    ) -> tuple[np.ndarray, list[tuple[int, str]]]:
        """q̇⁺ after the impulse of the contacts ``J`` and, per contact closing, (index, kind)."""
        if len(J) > MAX_CONTACTS:
            raise _RunFailure(
                f"{len(J)} contacts touch at once; at most {MAX_CONTACTS} are solved (by "
                "enumerating their active sets)"
            )
        M, Ab, _, _, gb = self.base.dae_blocks(t, q, qd)
        M, Ab = (x.toarray() if sps.issparse(x) else np.asarray(x) for x in (M, Ab))
        Ac = self.contacts.gaps(t, q)[1][J]
        speeds = -rate[J]
        e = np.where(speeds <= self.rest_speed, 0.0, self.e[J])
        rb = -np.asarray(gb, dtype=float)  # the bilateral rows' velocity defect, removed too
        res = impulse(M, Ab.reshape(self.mb, len(q)), rb, Ac, rate[J], e, qd)
        if res is None:
            raise _RunFailure(
                "no impulse satisfies the contacts "
                f"{', '.join(self.contacts.names[j] for j in J)} at this impact"
            )
        self.impact_work += res.work
        kinds = [
            (j, "rest" if s <= self.rest_speed else "impact")
            for j, s in zip(J, speeds, strict=True)
            if s > 0.0
        ]
        return qd + res.dqd, kinds

    def _settle(
        self, t: float, q: np.ndarray, qd: np.ndarray, closed: list[int]
    ) -> tuple[list[int], np.ndarray, np.ndarray]:
        """Close ``closed``, opening the contact of the most negative multiplier while any
        pulls; the state projected onto the mode's constraints."""
        while True:
            mask = tuple(j in closed for j in range(self.k))
            model = self.model(mask)
            q2, qd2, _ = Projector(model, tol=self.tol)(t, q, qd)
            if not closed:
                return closed, q2, qd2
            lam = model.solve(t, q2, qd2)[1][self.mb :]
            scale = 1e-12 * (1.0 + float(np.abs(lam).max(initial=0.0)))
            worst = int(np.argmin(lam))
            if lam[worst] >= -scale:
                return closed, q2, qd2
            closed.pop(worst)


def _gap(run: ContactRun, j: int, t0: float | None) -> Callable:
    """The closing event of open contact j: its gap, or gap/(t − t0) when it opened at t0."""

    def gap(t: float, q: np.ndarray, qd: np.ndarray) -> float:
        g, rate = run.gaps(t, q, qd)
        if t0 is None:
            return float(g[j])
        dt = t - t0
        return float(rate[j]) if dt <= root_tolerance(t0) else float(g[j]) / dt

    return gap


def _multiplier(model: Any, row: int) -> Callable:
    """The release event of a closed contact: its multiplier (row ``row`` of the mode's λ)."""

    def lam(t: float, q: np.ndarray, qd: np.ndarray) -> float:
        return float(model.solve(t, q, qd)[1][row])

    return lam


class Segments:
    """The states of a contact run's segments: each segment's model, its records, the impact
    work to each recorded state: the ``run`` the trajectory is built from (``T``, ``Q``, ``QD``,
    ``W``, ``IW``, ``switches``, ``records``), and its per-segment evaluation."""

    def __init__(self, contacts: ContactRun) -> None:
        self.contacts = contacts
        self.parts: list[tuple[tuple[bool, ...], int]] = []  # (mode, number of states)
        self.T: list[float] = []
        self.Q: list[np.ndarray] = []
        self.QD: list[np.ndarray] = []
        self.W: list[float] = []
        self.IW: list[float] = []
        self.switches: list = []
        self.records: list[EventRecord] = []
        self.work = 0.0  # of the applied forces up to the current segment

    def add(self, mode: tuple[bool, ...], run: Any, fired: bool) -> None:
        """The states of one segment's run; ``fired``: it ended at a contact's event (its last
        record, which the contact's own records replace)."""
        k = len(run.T)
        self.parts.append((mode, k))
        self.T += run.T
        self.Q += run.Q
        self.QD += run.QD
        self.W += [w + self.work for w in run.W]
        self.IW += [self.contacts.impact_work] * k
        self.switches += run.switches
        self.records += run.records[:-1] if fired else run.records
        if run.W:
            self.work = self.W[-1]

    def evaluate_states(self, T: np.ndarray, Q: np.ndarray, QD: np.ndarray) -> dict:
        """q̈, λ (bilateral, then one column per contact: 0 while open), f (the gap while
        open), g, the energies and the dropped rows at the recorded states, per segment."""
        c, mb, k = self.contacts, self.contacts.mb, self.contacts.k
        out: dict[str, list] = {}
        start = 0
        for mode, count in self.parts:
            if not count:
                continue
            sl = slice(start, start + count)
            start += count
            ev = c.model(mode).evaluate_states(T[sl], Q[sl], QD[sl])
            res = ev.get("residual")
            f, g = (res[:, 0], res[:, 1]) if res is not None else (ev["f"], ev["g"])
            lam = np.zeros((count, mb + k))
            F, G = np.zeros((count, mb + k)), np.zeros((count, mb + k))
            cols = list(range(mb)) + [mb + j for j in range(k) if mode[j]]
            lam[:, cols], F[:, cols], G[:, cols] = ev["multipliers"], f, g
            for j in (j for j in range(k) if not mode[j]):
                F[:, mb + j] = [
                    c.gaps(t, q, qd)[0][j] for t, q, qd in zip(T[sl], Q[sl], QD[sl], strict=True)
                ]
            opened = np.zeros((count, mb + k), dtype=bool)
            opened[:, [mb + j for j in range(k) if not mode[j]]] = True
            parts = {"qdd": ev["qdd"], "multipliers": lam, "f": F, "g": G, "open": opened}
            for key in ("T", "V", "T0", "T2"):
                parts[key] = ev[key]
            parts["redundant_rows"] = ev.get("redundant_rows", np.zeros(count, dtype=np.int64))
            for key, v in parts.items():
                out.setdefault(key, []).append(np.asarray(v))
        return {key: np.concatenate(v) for key, v in out.items()}


class Layout:
    """What the trajectory reads of a contact run's model: the base model's names and fields
    with one more constraint row per contact, and the per-segment evaluation."""

    def __init__(self, model: Any, segments: Segments) -> None:
        mb, k = model.m, segments.contacts.k
        self.n, self.m = model.n, mb + k
        self.coordinate_names = model.coordinate_names
        self.multiplier_names = [
            *model.multiplier_names,
            *(f"lambda{mb + j + 1}" for j in range(k)),
        ]
        self.holonomic = np.concatenate([np.asarray(model.holonomic, dtype=bool), np.ones(k, bool)])
        self.parameters, self.geometry = model.parameters, model.geometry
        self.evaluate_states = segments.evaluate_states


def run_segments(
    contacts: ContactRun,
    t0: float,
    q0: np.ndarray,
    qd0: np.ndarray,
    t1: float,
    user: UserEvents,
    start: Callable[..., Any],
) -> tuple[str, str, Segments, dict, list]:
    """Run segment after segment to ``t1``. ``start(model, t, q, qd, events)`` makes and runs
    one segment (the driver's ``_Run``) and returns it with its status and message. Returns
    the status, message, the segments, the summed statistics and the projectors used."""
    segs = Segments(contacts)
    contacts.check_gaps(t0, q0, qd0)
    mode = (False,) * contacts.k
    try:
        mode, q, qd, kinds = contacts.transition(t0, q0, qd0, mode)
    except _RunFailure as err:  # the run cannot start
        raise SimulationError(f"at the initial state: {err}") from None
    _record(segs, kinds, t0, q, qd)
    t, stats, projectors, repeats = t0, {}, [], 0
    n_user = len(user.events)
    while True:
        evs = contacts.events(mode, t, q)
        events = UserEvents([*user.events, *evs])
        events.counts[:n_user] = user.counts
        try:
            run, status, message, projector = start(contacts.model(mode), t, q, qd, events)
        except (_RunFailure, *NUMERICAL) as err:  # the method could not start from this state
            return "failed", f"failed at t = {t:.17g}: {err}", segs, stats, projectors
        projectors.append(projector)
        user.counts = events.counts[:n_user]
        fired = [i - n_user for i, c in enumerate(events.counts[n_user:], n_user) if c]
        segs.add(mode, run, bool(fired))  # a contact's event is terminal: the last root
        for key, v in [*run.finish().items(), ("cpu_time", run.cpu)]:
            if isinstance(v, int | float):
                stats[key] = stats.get(key, 0) + v
        if status != "success" or not fired or not run.T:
            return status, message, segs, stats, projectors
        t_new = run.T[-1]
        repeats = repeats + 1 if t_new - t <= root_tolerance(t) else 0
        if repeats > MAX_REPEATS:
            return (
                "failed",
                f"failed at t = {t_new:.17g}: {MAX_REPEATS} contact events without time "
                "advancing (the contacts chatter: raise rest_speed)",
                segs, stats, projectors,
            )  # fmt: skip
        j = fired[0]
        q, qd = run.Q[-1], run.QD[-1]
        released = j if mode[j] else None
        try:
            mode, q, qd, kinds = contacts.transition(t_new, q, qd, mode, released)
        except (_RunFailure, *NUMERICAL) as err:
            return "failed", f"failed at t = {t_new:.17g}: {err}", segs, stats, projectors
        _record(segs, kinds, t_new, q, qd)
        t = t_new
        stats["contact_events"] = stats.get("contact_events", 0) + 1
        if t >= t1:
            return "success", "reached the end of the time span", segs, stats, projectors


def _record(segs: Segments, kinds: list[tuple[str, str]], t: float, q, qd) -> None:
    for name, kind in kinds:
        segs.records.append(EventRecord(name, t, np.array(q), np.array(qd), kind))
