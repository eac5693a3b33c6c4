"""What a sweep's task does in a worker process: compile once, then run a batch of grid points.

A task carries the compiled model, pickled (a model file's is compiled once by the driver), or
else the model file's text (a few kilobytes, not code: it is read with
:func:`pfaff.load_model`, which executes nothing) and the indices of its runs. Each process keeps
the models it compiled in :data:`_MODELS`, keyed by the SHA-256 of the text: the file is derived
and compiled at most once per process, and each run takes its parameter values through
:meth:`pfaff.NumericModel.with_parameters` (microseconds). A run that fails (a singular
configuration, a blow-up, an inconsistent initial state, a bad parameter value) is reported as
its status and message, never raised.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import tempfile
import threading
import time
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pfaff.core.errors import PfaffError
from pfaff.integrate.pace import TimeLimit
from pfaff.integrate.simulation import simulate
from pfaff.modelfile import ModelFile, load_model
from pfaff.sweep.grid import Grid

CACHED_MODELS = 4  # models kept per process (a worker serving several sweeps)
_MODELS: OrderedDict[str, _Compiled] = OrderedDict()
_LOCK = threading.Lock()  # one run at a time per cached model (kernels own their buffers)


@dataclass(frozen=True)
class SweepSpec:
    """Everything a task needs: the file, the base values, the grid and the run settings.

    Attributes
    ----------
    text : str
        The model file's text.
    filename : str
        Its name (for messages).
    parameters : dict of str to float
        Base parameter values (the file's, or those of the :class:`pfaff.ModelFile` given).
    q0, qd0 : tuple of float
        Base initial state, in coordinate order.
    coordinates : tuple of str
        Coordinate names, in order (for ``q0.<name>``).
    grid : Grid
    t_eval : ndarray, shape (samples,)
    options : dict
        Keyword arguments of :func:`pfaff.simulate` (method, tolerances, ...).
    model : bytes or None
        The compiled model, pickled by the driver (:func:`pfaff.sweep.source.shipped_model`);
        None: each worker process derives and compiles the file itself.
    """

    text: str
    filename: str
    parameters: dict[str, float]
    q0: tuple[float, ...]
    qd0: tuple[float, ...]
    coordinates: tuple[str, ...]
    grid: Grid
    t_eval: np.ndarray
    options: dict[str, Any] = field(default_factory=dict)
    model: bytes | None = None

    @property
    def key(self) -> str:
        """SHA-256 of the file's text and the shipped model: the key in a worker's cache."""
        digest = hashlib.sha256(self.text.encode())
        digest.update(self.model or b"")
        return digest.hexdigest()

    def run_inputs(self, i: int) -> tuple[dict[str, float], np.ndarray, np.ndarray]:
        """Parameter values, q0 and q̇0 of run ``i``."""
        params, q0, qd0 = dict(self.parameters), np.array(self.q0), np.array(self.qd0)
        index = {c: j for j, c in enumerate(self.coordinates)}
        for name, v in self.grid.point(i).items():
            kind, _, coord = name.partition(".")
            if kind == "q0" and coord in index:
                q0[index[coord]] = v
            elif kind == "qd0" and coord in index:
                qd0[index[coord]] = v
            else:
                params[name] = v
        return params, q0, qd0


class _Compiled:
    """A model file loaded and derived in this process, and its first compiled model."""

    def __init__(self, spec: SweepSpec) -> None:
        self.base: Any = None
        if spec.model is not None:  # compiled by the driver: nothing derived here
            self.base = pickle.loads(spec.model)  # (pfaff's own pickle, made by the driver)
            self.used = set(self.base.parameters)
            self.lock = threading.Lock()
            return
        with tempfile.TemporaryDirectory(prefix="pfaff-sweep-") as tmp:
            path = Path(tmp) / (Path(spec.filename).name or "model.toml")
            path.write_text(spec.text, encoding="utf-8")
            self.file: ModelFile = load_model(path, max_bytes=max(len(spec.text.encode()), 1))
        self.eom = self.file.system.equations()
        self.used = {s.name for s in self.eom.parameters}
        self.lock = threading.Lock()

    def model(self, params: dict[str, float]) -> Any:
        """The compiled model with these values: the shipped (or first compiled) model's
        ``with_parameters``, general models and families alike."""
        values = {k: v for k, v in params.items() if k in self.used}
        if self.base is None:
            self.base = self.eom.compile(values)
            return self.base
        return self.base.with_parameters(values)


def compiled(spec: SweepSpec) -> _Compiled:
    """The process's compiled model of ``spec``'s file (derived on first use)."""
    key = spec.key
    with _LOCK:
        entry = _MODELS.get(key)
        if entry is None:
            entry = _MODELS[key] = _Compiled(spec)
            while len(_MODELS) > CACHED_MODELS:
                _MODELS.popitem(last=False)
        _MODELS.move_to_end(key)
    return entry


def run_batch(spec: SweepSpec, indices: list[int]) -> dict[str, Any]:
    """Run the grid points ``indices`` of ``spec``: the task of a sweep.

    Returns
    -------
    dict
        ``index`` (k,), ``status`` and ``message`` (lists of k str), ``q``, ``qd`` (k, samples,
        n), ``multipliers`` (k, samples, m) (NaN past a failure), ``energy_error`` and
        ``constraint_residual`` (k,) (the largest absolute energy balance and constraint residual
        of the run), ``seconds`` (k,) per run, the model's ``coordinate_names``,
        ``multiplier_names`` and ``constraint_names``, and the worker's ``pid``.

    Examples
    --------
    >>> import pfaff, numpy as np
    >>> from pfaff.sweep.grid import Grid
    >>> text = '''
    ... [model]
    ... coordinates = ["x"]
    ... parameters = { m = 1.0, k = 4.0 }
    ... kinetic = "m*dot(x)**2/2"
    ... potential = "k*x**2/2"
    ... '''
    >>> spec = SweepSpec(text, "spring.toml", {"m": 1.0, "k": 4.0}, (1.0,), (0.0,), ("x",),
    ...                  Grid(("k",), (np.array([1.0, 4.0]),)), np.linspace(0, np.pi, 3))
    >>> out = run_batch(spec, [0, 1])
    >>> out["status"], np.round(out["q"][:, -1, 0], 6).tolist()  # cos(sqrt(k) t) at t = pi
    (['success', 'success'], [-1.0, 1.0])
    """
    entry = compiled(spec)
    k, s, n = len(indices), len(spec.t_eval), len(spec.q0)
    out: dict[str, Any] = {"index": np.asarray(indices, dtype=np.int64), "pid": os.getpid()}
    out["status"], out["message"] = [], []
    out["seconds"], out["energy_error"], out["constraint_residual"] = (
        np.full(k, np.nan) for _ in range(3)
    )
    q, qd, lam = np.full((k, s, n), np.nan), np.full((k, s, n), np.nan), None
    names: dict[str, list[str]] = {}
    with entry.lock:
        for j, i in enumerate(indices):
            start = time.perf_counter()
            traj, status, message = _run(entry, spec, int(i))
            out["seconds"][j] = time.perf_counter() - start
            out["status"].append(status)
            out["message"].append(message)
            if traj is None:
                continue
            if lam is None:
                lam = np.full((k, s, traj.multipliers.shape[1]), np.nan)
            keep = np.isin(traj.t, spec.t_eval)  # not the states of events between samples
            rows = _rows(spec.t_eval, traj.t[keep])
            q[j, rows], qd[j, rows] = traj.q[keep], traj.qd[keep]
            lam[j, rows] = traj.multipliers[keep]
            if len(traj.t):
                out["energy_error"][j] = float(np.abs(traj.energy_balance).max())
                res = np.abs(traj.constraint_residual)
                res[:, 0][traj.contact_open] = 0.0  # an open contact's gap is no residual
                out["constraint_residual"][j] = float(res.max(initial=0.0))
        if entry.base is not None:
            names = _names(entry.base)
    out.update(q=q, qd=qd, multipliers=lam, **names)
    return out


def _run(entry: _Compiled, spec: SweepSpec, i: int) -> tuple[Any, str, str]:
    """One run: (trajectory or None, status, message); nothing raised but Ctrl-C and the like."""
    try:
        params, q0, qd0 = spec.run_inputs(i)
        model = entry.model(params)
        span = (float(spec.t_eval[0]), float(spec.t_eval[-1]))
        traj = simulate(model, q0, qd0, span, t_eval=spec.t_eval, progress=False, **spec.options)
    except PfaffError as e:
        return None, "failed", str(e)
    except Exception as e:  # a failure in the user's equations (overflow, ...) or a bug
        return None, "failed", f"{type(e).__name__}: {e}"
    if traj.status == "interrupted":  # Ctrl-C (in this process): stop the sweep, not the run
        raise KeyboardInterrupt
    if traj.status == "failed" and traj.message.startswith(TimeLimit.verb):
        return traj, "timeout", traj.message  # over the sweep's run_timeout: the sweep goes on
    return traj, traj.status, traj.message


def _rows(t_eval: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The rows of ``t_eval`` a trajectory's reported times are (a failed run stops early)."""
    rows = np.clip(np.searchsorted(t_eval, t), 0, len(t_eval) - 1)
    below = np.clip(rows - 1, 0, None)
    closer = np.abs(t_eval[below] - t) < np.abs(t_eval[rows] - t)
    return np.where(closer, below, rows)


def _names(model: Any) -> dict[str, list[str]]:
    names = {
        "coordinate_names": list(model.coordinate_names),
        "multiplier_names": list(model.multiplier_names),
        "constraint_names": list(model.constraint_names),
    }
    return with_contacts(names, getattr(getattr(model, "contacts", None), "names", ()))


def with_contacts(names: dict[str, list[str]], contacts: Sequence[str]) -> dict[str, list[str]]:
    """``names`` with one multiplier and constraint row per unilateral constraint (named in
    ``contacts``), after the bilateral ones: the columns of a contact run's multipliers."""
    for c in contacts:
        names["multiplier_names"].append(f"lambda{len(names['multiplier_names']) + 1}")
        names["constraint_names"].append(c)
    return names
