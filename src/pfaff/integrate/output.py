"""``simulate(..., output=path)``: the reported states written to a file as the run reports them.

With ``output="run.nc"`` every reported state is evaluated (q̈, λ, energies, residuals) and
appended to a netCDF file at once, time its record dimension
(:class:`pfaff.results.ncfile.RecordWriter`), then dropped: a run keeps one state in memory
whatever its length and its number of reported times (2^24 particles, 11 states: 22.8 GB in
memory, a few hundred MB resident streamed). The file is written beside the target under a
temporary name and renamed onto it when the run ends, also when it ends early (Ctrl-C, a
failure, ``max_steps``, ``max_seconds``): the states so far, with the status and message in the
file's attributes. A bug raised out of ``simulate`` removes the temporary file; the target is
never a half-written file. The returned :class:`pfaff.Trajectory` reads its per-state arrays from
the file (read-only memory maps, nothing read until used; ``traj.output`` is the path).

``output="run.csv"`` writes the trajectory (in memory, as without ``output``) with
:meth:`pfaff.Trajectory.to_csv` when the run ends; a CSV of more than :data:`CSV_COLUMNS`
columns (one per coordinate, speed, acceleration, multiplier and residual) is refused before the
run starts.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pfaff.core.errors import OptionError
from pfaff.core.files import atomic_path
from pfaff.results.ncfile import RecordWriter, char_array, read_variables
from pfaff.results.trajectory import Trajectory

if TYPE_CHECKING:
    from pfaff.numeric.protocol import DynamicsModel

CSV_COLUMNS = 1 << 16  # the widest CSV written (2^24 particles would be 10^8 columns)
NAMES = 1 << 16  # coordinate and multiplier names stored in a netCDF file up to this many
_ENERGIES = ("kinetic", "potential", "energy", "jacobi", "nc_work", "impact_work")


def output_kind(output: object, n: int, m: int) -> str | None:
    """ "nc", "csv" or None for ``simulate(output=...)``, checked before the run starts.

    Examples
    --------
    >>> output_kind("run.nc", 3, 1), output_kind(None, 3, 1)
    ('nc', None)
    """
    if output is None:
        return None
    if not isinstance(output, str | os.PathLike):
        raise OptionError(f"`output` must be a file name ending in .nc or .csv; got {output!r:.80}")
    suffix = Path(output).suffix.lower()
    if suffix not in (".nc", ".csv"):
        raise OptionError(f"`output` must end in .nc (netCDF) or .csv; got {str(output)!r:.80}")
    columns = 1 + 3 * n + 3 * m + 6  # t; q, q̇, q̈; λ, f, g; T, V, E, Jacobi, W, balance
    if suffix == ".csv" and columns > CSV_COLUMNS:
        raise OptionError(
            f"`output`: a CSV of {columns} columns (n = {n} coordinates) is refused, more than "
            f"{CSV_COLUMNS}; write netCDF instead (output='{Path(output).stem}.nc'), which "
            "stores each reported state as one record as the run goes"
        )
    return suffix[1:]


class StreamedStates:
    """The reported states of one run appended to a netCDF file (see the module docstring).

    Parameters
    ----------
    model : DynamicsModel
        The run's model (its ``evaluate_states`` evaluates each state as it is reported).
    path : path-like
        The target file.
    attrs : dict
        Global attributes known at the start (method, parameters).
    """

    def __init__(self, model: DynamicsModel, path: str | os.PathLike, attrs: dict) -> None:
        self.model, self.path = model, Path(path)
        n, m = model.n, model.m
        self._stack = contextlib.ExitStack()
        self.tmp = self._stack.enter_context(atomic_path(path))
        dims: dict[str, int] = {"coordinate": n, "level": 2}
        variables: list[tuple] = [("time", ("time",), "f8")]
        variables += [(k, ("time", "coordinate"), "f8") for k in ("q", "qd", "qdd")]
        if m:
            dims["multiplier"] = m
            variables.append(("multipliers", ("time", "multiplier"), "f8"))
        variables += [(k, ("time",), "f8") for k in (*_ENERGIES, "energy_balance")]
        if m:
            variables.append(("constraint_residual", ("time", "level", "multiplier"), "f8"))
        variables.append(("redundant_rows", ("time",), "i4"))
        for dim, names in (("coordinate", model.coordinate_names), ("multiplier", model.multiplier_names)):  # fmt: skip
            if 0 < len(names) <= NAMES:
                chars = char_array([str(s) for s in names])
                dims[f"{dim}_strlen"] = chars.shape[1]
                variables.append((dim, (dim, f"{dim}_strlen"), "S1", chars))
        variables.append(("level", ("level", "level_strlen"), "S1", char_array(["position", "velocity"])))  # fmt: skip
        dims["level_strlen"] = 8
        self.attrs = {**attrs, "status": "running", "message": "", "multipliers": m}
        self.writer = RecordWriter(self.tmp, dims, variables, self.attrs)
        self._holonomic = np.asarray(model.holonomic, dtype=bool)
        self._e0: float | None = None

    def take(self, t: list, q: list, qd: list, w: list, keep: bool = True) -> None:
        """Evaluate and append the last recorded state, then keep only it in the run's lists
        (its time alone unless ``keep``: a user event's record copies its state)."""
        ti, qi, qdi = t[-1], q[-1], qd[-1]
        ev = self.model.evaluate_states(np.array([ti]), qi[None], qdi[None])
        res = ev.get("residual")
        if res is None:
            res = np.stack([ev["f"], ev["g"]], axis=1)
        res[:, 0, ~self._holonomic] = 0.0
        energy = float(ev["T"][0] + ev["V"][0])
        if self._e0 is None:
            self._e0 = energy
        values = {
            "time": ti, "q": qi, "qd": qdi, "qdd": ev["qdd"][0], "multipliers": ev["multipliers"][0],
            "kinetic": ev["T"][0], "potential": ev["V"][0], "energy": energy,
            "jacobi": ev["T2"][0] - ev["T0"][0] + ev["V"][0], "nc_work": w[-1], "impact_work": 0.0,
            "energy_balance": energy - self._e0 - w[-1], "constraint_residual": res[0],
            "redundant_rows": int(ev.get("redundant_rows", np.zeros(1))[0]),
        }  # fmt: skip
        self.writer.append(values)
        for rows in (t, q, qd, w):
            del rows[:-1]
        if not keep:
            q[-1] = qd[-1] = None

    def finish(self, status: str, message: str, stats: dict) -> Path:
        """The final attributes written, the file renamed onto the target; its path."""
        attrs = {**self.attrs, "status": status, "message": message[:4000]}
        attrs |= {f"stat_{k}": v for k, v in stats.items() if _number(v)}
        self.writer.finish(attrs)
        self._stack.close()  # the rename
        return self.path

    def abort(self) -> None:
        """Close and remove the temporary file (an exception left the run)."""
        self.writer.close()
        self._stack.__exit__(RuntimeError, RuntimeError("aborted"), None)

    def trajectory(self, fields: dict) -> Trajectory:
        """The run as a :class:`Trajectory` whose per-state arrays are memory maps of the file;
        ``fields`` the rest (status, message, stats, method, names, projector, events...)."""
        v, _ = read_variables(self.path)
        k, m = len(v["time"]), self.model.m
        multipliers = v["multipliers"] if m else np.zeros((k, 0))
        res = v["constraint_residual"] if m else np.zeros((k, 2, 0))
        return Trajectory(
            t=v["time"], q=v["q"], qd=v["qd"], qdd=v["qdd"], multipliers=multipliers,
            kinetic=v["kinetic"], potential=v["potential"], jacobi=v["jacobi"],
            nc_work=v["nc_work"], impact_work=v["impact_work"], constraint_residual=res,
            redundant_rows=v["redundant_rows"],
            contact_open=np.broadcast_to(np.False_, (k, m)), output=self.path, **fields,
        )  # fmt: skip


def _number(v: object) -> bool:
    return isinstance(v, int | float | np.integer | np.floating) and not isinstance(v, bool)


def streamed(run, model, output, method: str, projector, project_output: bool, start: tuple,
             throw: bool) -> Trajectory:  # fmt: skip
    """Run ``run`` (the driver's stepping loop, ``simulation._Run``) with its states streamed to
    ``output``; the file finished and renamed whatever the status, removed on an exception."""
    from pfaff.core.errors import SimulationError

    params = {f"parameter_{k}": float(v) for k, v in model.parameters.items()}
    sink = StreamedStates(model, output, {"method": method, **params})
    run.sink = sink
    try:
        status, message = run.go(*start)
        stats = {**run.finish(), **projector.stats, "cpu_time": run.cpu}
        sink.finish(status, message, stats)
    except BaseException:
        sink.abort()
        raise
    if status != "success" and throw:
        raise SimulationError(f"{message} (the states so far are in {output})")
    return sink.trajectory(
        dict(
            stats=stats, status=status, message=message, method=method,
            coordinate_names=model.coordinate_names, multiplier_names=model.multiplier_names,
            parameters=dict(model.parameters), projector=projector if project_output else None,
            switches=list(run.switches), events=list(run.records), geometry=model.geometry,
        )
    )  # fmt: skip
