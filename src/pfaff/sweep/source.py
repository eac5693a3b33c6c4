"""What a sweep runs: a model file (read here, compiled once) or a compiled model, with its base
values, initial state, time span and run settings, checked before any run starts.

:func:`source` returns a :class:`Source` whatever the sweep was given, so the driver and the
workers see one kind of thing: a :class:`~pfaff.sweep.worker.SweepSpec` holding the pickled
compiled model (or, for a file that does not compile with its own values, the file's text), the
base parameter values, q₀, q̇₀ and the coordinate names ``q0.<name>`` refers to; and t₀ … t_end.
"""

from __future__ import annotations

import math
import os
import pickle
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from pfaff.core.errors import OptionError, PfaffError
from pfaff.modelfile import ModelFile, load_model
from pfaff.numeric.checks import real_number, real_vector
from pfaff.numeric.value import ModelValue
from pfaff.sweep.grid import Grid
from pfaff.sweep.worker import SweepSpec, with_contacts

PASSED = ("t_end", "samples")  # [simulate] keys the sweep uses itself, not pfaff.simulate


@dataclass(frozen=True)
class Source:
    """A sweep's model and base run (see the module docstring).

    Attributes
    ----------
    name : str
        The model's name (the file's, or ``"compiled model"``).
    file : str or None
        The model file's path.
    base : SweepSpec
        What every task carries: the pickled model (or the file's text), the base parameter
        values, q₀, q̇₀, the coordinate names and the run settings; no grid or times yet.
    t0, t_end : float
    samples : int or None
        The file's ``[simulate] samples``.
    names : dict of str to list of str
        ``coordinate_names``, ``multiplier_names``, ``constraint_names`` (empty until known).
    modelfile : ModelFile or None
        The file, read.
    """

    name: str
    file: str | None
    base: SweepSpec
    t0: float
    t_end: float
    samples: int | None = None
    names: dict[str, list[str]] = field(default_factory=dict)
    modelfile: ModelFile | None = None

    def spec(self, grid: Grid, samples: int) -> SweepSpec:
        """The sweep's task description: the base with the grid and ``samples`` times."""
        return replace(self.base, grid=grid, t_eval=np.linspace(self.t0, self.t_end, samples))


def _base(text: str, filename: str, parameters: dict, q0: object, qd0: object, coordinates: list,
          options: dict, model: bytes | None) -> SweepSpec:  # fmt: skip
    return SweepSpec(
        text=text,
        filename=filename,
        parameters=parameters,
        q0=tuple(float(x) for x in q0),  # type: ignore[attr-defined]
        qd0=tuple(float(x) for x in qd0),  # type: ignore[attr-defined]
        coordinates=tuple(coordinates),
        grid=Grid((), ()),
        t_eval=np.empty(0),
        options=options,
        model=model,
    )


def source(
    model: object,
    *,
    q0: object = None,
    qd0: object = None,
    t_span: object = None,
    t_end: object = None,
    options: Mapping[str, Any] | None = None,
) -> Source:
    """The :class:`Source` of ``pfaff.sweep(model, ...)``: a file's path, a
    :class:`pfaff.ModelFile` or a compiled model; every argument checked (:class:`OptionError`,
    :class:`pfaff.StateError` naming it)."""
    if options is not None and not isinstance(options, Mapping):
        raise OptionError(
            f"`options` must be a dict of pfaff.simulate keywords, got {options!r:.60}"
        )
    if t_span is not None and t_end is not None:
        raise OptionError("give `t_span` or `t_end`, not both")
    if isinstance(model, ModelValue):
        return _compiled(model, q0, qd0, t_span, t_end, dict(options or {}))
    if isinstance(model, ModelFile | str | os.PathLike):
        return _file(model, q0, qd0, t_span, t_end, dict(options or {}))
    raise TypeError(
        "`model` must be a model file's path, a pfaff.ModelFile or a compiled model "
        f"(eom.compile(...)), got {type(model).__name__}"
    )


def _compiled(
    model: ModelValue, q0: object, qd0: object, t_span: object, t_end: object, options: dict
) -> Source:
    names = list(model.coordinate_names)
    if q0 is None:
        raise OptionError("a sweep of a compiled model needs `q0` (and `t_span`)")
    if t_span is None and t_end is None:
        raise OptionError("a sweep of a compiled model needs `t_span` = (t0, t_end)")
    start = real_vector(q0, "q0", len(names), names)
    speed = np.zeros(len(names)) if qd0 is None else real_vector(qd0, "qd0", len(names), names)
    t0, t1 = _span(t_span, t_end)
    pickled = pickle.dumps(model, protocol=pickle.HIGHEST_PROTOCOL)
    return Source(
        name="compiled model",
        file=None,
        base=_base("", "", dict(model.parameters), start, speed, names, options, pickled),
        t0=t0,
        t_end=t1,
        names=with_contacts(
            {
                "coordinate_names": names,
                "multiplier_names": list(model.multiplier_names),
                "constraint_names": list(model.constraint_names),
            },
            getattr(getattr(model, "contacts", None), "names", ()),
        ),
    )


def _file(
    model: ModelFile | str | os.PathLike,
    q0: object,
    qd0: object,
    t_span: object,
    t_end: object,
    options: dict,
) -> Source:
    mf = model if isinstance(model, ModelFile) else load_model(model)
    try:
        text = Path(mf.path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise OptionError(
            f"`model`: its file {mf.path} cannot be read again for the workers ({e})"
        ) from None
    coordinates = [str(getattr(q, "func", q)) for q in mf.system.coordinates]
    n = len(coordinates)
    start = mf.q0 if q0 is None else real_vector(q0, "q0", n, coordinates)
    speed = mf.qd0 if qd0 is None else real_vector(qd0, "qd0", n, coordinates)
    if t_span is None and t_end is None:
        if "t_end" not in mf.simulate:
            raise OptionError(
                f"no end time: pass `t_end` (--t-end) or set t_end in [simulate] of {mf.path}"
            )
        t_end = mf.simulate["t_end"]
    t0, t1 = _span(t_span, t_end)
    options = {**{k: v for k, v in mf.simulate.items() if k not in PASSED}, **options}
    return Source(
        name=mf.name,
        file=str(mf.path),
        base=_base(
            text,
            mf.path.name,
            dict(mf.parameters),
            start,
            speed,
            coordinates,
            options,
            shipped_model(mf),
        ),
        t0=t0,
        t_end=t1,
        samples=mf.simulate.get("samples"),
        modelfile=mf,
    )


def _span(t_span: object, t_end: object) -> tuple[float, float]:
    """(t0, t_end) from ``t_span`` or from ``t_end`` (t0 = 0): finite, t_end > t0."""
    if t_span is None:
        if isinstance(t_end, bool) or not isinstance(t_end, int | float | np.floating | np.integer):
            raise OptionError(f"`t_end` must be a number, got {t_end!r:.40}")
        t0, t1 = 0.0, float(t_end)
        if not (math.isfinite(t1) and t1 > 0):
            raise OptionError(f"`t_end` must be positive and finite, got {t_end!r}")
        return t0, t1
    if isinstance(t_span, str | bytes | Mapping) or np.ndim(t_span) != 1 or len(t_span) != 2:
        raise OptionError(f"`t_span` must be a pair (t0, t_end), got {t_span!r:.60}")
    t0, t1 = (real_number(v, f"t_span[{i}]", OptionError) for i, v in enumerate(t_span))
    if not t1 > t0:
        raise OptionError(f"`t_span`: t_end must be after t0, got ({t0}, {t1})")
    return t0, t1


def shipped_model(mf: ModelFile) -> bytes | None:
    """The file's model derived and compiled once, here, and pickled for the workers (each
    unpickles it once per process instead of deriving and compiling the file); None when it
    does not compile with the file's values (each run then reports why)."""
    system = mf.system
    try:
        eom = system.equations()
        used = {s.name for s in eom.parameters}
        model = eom.compile({k: v for k, v in mf.parameters.items() if k in used})
    except PfaffError:
        return None
    return pickle.dumps(model, protocol=pickle.HIGHEST_PROTOCOL)


def names_of(src: Source) -> dict[str, list[str]]:
    """Coordinate, multiplier and constraint names of the source (derived from the file when
    every run failed before its model was compiled: the workers had none to report)."""
    if src.names or src.modelfile is None:
        return src.names
    system = src.modelfile.system
    eom = system.equations()
    names = {
        "coordinate_names": [str(q.func) for q in eom.coordinates],
        "multiplier_names": [str(s) for s in eom.multipliers],
        "constraint_names": list(eom.constraint_names),
    }
    return with_contacts(names, [c.name for c in system.contacts])
