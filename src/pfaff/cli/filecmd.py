"""``pfaff equations MODEL.toml`` and ``pfaff run MODEL.toml``: the CLI on a model file (or a
URDF robot, ``pfaff run robot.urdf --t-end T --q0 joint=value``)."""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from pfaff.cli.argtypes import positive, whole
from pfaff.cli.jsontext import dumps
from pfaff.cli.signals import stage, verbose
from pfaff.core.errors import RedundancyWarning

RUN_FLAGS = ("t_end", "method", "rtol", "atol")
REPORTED = 201  # equally spaced times `pfaff run` reports by default


def add_parsers(sub: argparse._SubParsersAction, common: Any) -> None:
    """The ``equations`` and ``run`` subcommands; ``common(p)`` adds the shared options."""
    from pfaff.integrate.simulation import METHODS

    eq = sub.add_parser("equations", help="derive and print the equations of a model file")
    eq.add_argument("model", metavar="MODEL.toml", help="the model file (or a URDF file)")
    eq.add_argument("--latex", action="store_true", help="print LaTeX (default: text)")
    eq.add_argument("--json", action="store_true", help="print one JSON object (default: text)")
    eq.add_argument(
        "--max-bytes", type=whole(1), default=None, help="the file-size cap (default: 1 MB)"
    )
    common(eq)
    run = sub.add_parser("run", help="simulate a model file")
    run.add_argument("model", metavar="MODEL.toml", help="the model file (or a URDF file)")
    run.add_argument(
        "--t-end", type=positive, help="end time (default: the file's [simulate] t_end)"
    )
    run.add_argument(
        "--method",
        choices=list(METHODS),
        help="integrator (default: the file's [simulate] method, else projection)",
    )
    run.add_argument(
        "--rtol", type=positive, help="relative tolerance (default: the file's, else 1e-9)"
    )
    run.add_argument(
        "--atol", type=positive, help="absolute tolerance (default: the file's, else 1e-11)"
    )
    times = run.add_mutually_exclusive_group()
    times.add_argument(
        "--samples",
        type=whole(2),
        help=f"report this many equally spaced times (default: the file's [simulate] samples, "
        f"else {REPORTED}; fewer for a family whose states would not fit in 1 GiB)",
    )
    times.add_argument(
        "--steps",
        action="store_true",
        help="report the integrator's own steps instead (default: equally spaced times)",
    )
    run.add_argument(
        "--output", metavar="run.nc|run.csv", help="write the trajectory (default: not written)"
    )
    run.add_argument("--plot", metavar="run.png", help="write a figure of the run (default: none)")
    run.add_argument(
        "--animate", metavar="run.gif", help="write an animation of the run (default: none)"
    )
    run.add_argument(
        "--frames",
        type=whole(1, "needs at least 1 frame, got {v}"),
        default=200,
        help="animation frames (default: 200)",
    )
    run.add_argument(
        "--q0",
        nargs="+",
        metavar="NAME=VALUE",
        help="initial coordinates by name (default: the file's [initial]; a URDF file's joints: q0 = q̇0 = 0)",
    )
    run.add_argument("--json", action="store_true", help="print one JSON object (default: text)")
    run.add_argument(
        "--max-bytes", type=whole(1), default=None, help="the file-size cap (default: 1 MB)"
    )
    common(run)


def _load(args: argparse.Namespace) -> Any:
    """The model file, or a URDF file (``*.urdf``) as one: its values, q0 = q̇0 = 0, no
    [simulate] settings; ``--q0 name=value`` (``run``) sets initial angles by joint name."""
    from pfaff.modelfile import load_model

    stage("loading")
    if not str(args.model).lower().endswith(".urdf"):
        kw = {} if args.max_bytes is None else {"max_bytes": args.max_bytes}
        return _initial(load_model(args.model, **kw), getattr(args, "q0", None), {})
    from pfaff.core.errors import OptionError
    from pfaff.modelfile.load import ModelFile
    from pfaff.modelfile.urdf import MAX_BYTES, load_urdf

    if args.max_bytes is not None:
        raise OptionError(f"`--max-bytes` is for model files; a URDF file may have {MAX_BYTES}")
    system = load_urdf(args.model)
    zeros = np.zeros(system.n)
    path = Path(args.model)
    name = system.urdf_name or path.stem
    mf = ModelFile(path, name, system, dict(system.urdf_values), zeros, zeros.copy())
    joints = {jn: str(q.func) for jn, q in system.urdf_coordinates.items()}
    return _initial(mf, getattr(args, "q0", None), joints)


def _initial(mf: Any, pairs: list[str] | None, aliases: dict[str, str]) -> Any:
    """``mf`` with the initial coordinates ``name=value`` of ``--q0`` (a name: a coordinate, or
    a URDF joint in ``aliases``); the value a finite number, never evaluated."""
    from pfaff.core.errors import OptionError

    names = [str(q.func) for q in mf.system.coordinates]
    for pair in pairs or []:
        name, sep, text = pair.partition("=")
        name = aliases.get(name.strip(), name.strip())
        if not sep or name not in names:
            raise OptionError(
                f"`--q0 {pair[:60]}`: expected name=value with a coordinate name "
                f"({', '.join([*aliases, *names][:20])})"
            )
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not np.isfinite(value):
            raise OptionError(f"`--q0 {pair[:60]}`: the value must be a finite number")
        mf.q0[names.index(name)] = value
    return mf


def run_equations(args: argparse.Namespace) -> int:
    """Print M, Q − h, A, b, the Lagrange equations and the work table of a model file."""
    from pfaff.modelfile.printer import FileSyntax

    mf = _load(args)
    stage("deriving")
    with warnings.catch_warnings():  # (the sets are reported below, not as a Python warning)
        warnings.simplefilter("ignore", RedundancyWarning)
        eom = mf.system.equations()
    stage("printing")
    coords = list(eom.coordinates)
    fs = FileSyntax(coords)
    lagrange = [f"{fs(e.lhs)} = {fs(e.rhs)}" for e in eom.lagrange_equations]
    work = []
    with warnings.catch_warnings():  # (reported below)
        warnings.simplefilter("ignore", RedundancyWarning)
        works = mf.system.work() if mf.system.n <= 60 else []
    if works:
        for w in works:
            does = w.does_work()
            work.append(
                {
                    "name": w.name,
                    "generalized_force": [fs(e) for e in w.generalized_force],
                    "virtual_power": fs(w.virtual_power),
                    "does_work": does,
                }
            )
    rep = {
        "model": mf.name,
        "coordinates": [str(q.func) for q in coords],
        "parameters": mf.parameters,
        "mass_matrix": fs.matrix(eom.mass_matrix),
        "forcing": [fs(e) for e in eom.forcing],
        "constraint_matrix": fs.matrix(eom.constraint_matrix),
        "constraint_bias": [fs(e) for e in eom.constraint_bias],
        "constraint_names": list(eom.constraint_names),
        "multipliers": [str(s) for s in eom.multipliers],
        "lagrange_equations": lagrange,
        "work": work,
        "redundant_sets": [list(x) for x in eom.redundant_sets],
    }
    if args.json:
        print(dumps(rep))
    elif args.latex:
        print(eom.latex())
    else:
        print(_text(rep))
    return 0


def _text(rep: dict) -> str:
    lines = [f"{rep['model']}: q = ({', '.join(rep['coordinates'])})", "", "M ="]
    lines += [f"  [{', '.join(row)}]" for row in rep["mass_matrix"]]
    lines += ["", "Q − h ="] + [f"  {e}" for e in rep["forcing"]]
    if rep["multipliers"]:
        lines += ["", "A ="] + [f"  [{', '.join(row)}]" for row in rep["constraint_matrix"]]
        lines += ["", "b ="] + [f"  {e}" for e in rep["constraint_bias"]]
        pairs = zip(rep["multipliers"], rep["constraint_names"], strict=True)
        lines += ["", "multipliers: " + ", ".join(f"{m} ({c})" for m, c in pairs)]
    lines += _redundancy_lines(rep["redundant_sets"])
    lines += ["", "Lagrange's equations:"] + [f"  {e}" for e in rep["lagrange_equations"]]
    if rep["work"]:
        lines += ["", "Work of the applied forces:"]
        for w in rep["work"]:
            verdict = {True: "does work", False: "does no work", None: "undecided"}[w["does_work"]]
            lines.append(f"  {w['name']}: virtual power {w['virtual_power']} — {verdict}")
    return "\n".join(lines)


def _redundancy_lines(sets: list[list[str]]) -> list[str]:
    """The redundancy diagnosis: each set of constraints that depend on one another."""
    if not sets:
        return []
    lines = ["", "Redundant constraints (the motion is determined; on these rows only Aᵀλ is, the"]
    lines.append("multipliers reported are the minimum-norm ones):")
    return lines + ["  " + ", ".join(x) for x in sets]


def _run_redundancy(model: Any, traj: Any) -> list[list[str]]:
    """The dependent sets of a run's constraints at its last state (empty when none)."""
    from pfaff.numeric.rank import redundant_sets

    if not len(traj.t) or not int(np.max(traj.redundant_rows, initial=0)):
        return []
    A = model.constraint_matrix(float(traj.t[-1]), traj.q[-1])
    A = A.toarray() if hasattr(A, "toarray") else A
    names = list(model.constraint_names)
    return [[names[i] for i in rows] for rows in redundant_sets(A)]


def run_model(args: argparse.Namespace) -> int:
    """Simulate a model file with its settings, flags overriding them; exit 3 on failure."""
    from pfaff.core.errors import OptionError
    from pfaff.integrate.simulation import simulate

    mf = _load(args)
    settings = dict(mf.simulate)
    for key in RUN_FLAGS:
        if getattr(args, key) is not None:
            settings[key] = getattr(args, key)
    if args.samples is not None:
        settings["samples"] = args.samples
    t_end = settings.pop("t_end", None)
    if t_end is None:
        raise OptionError(f"{args.model}: no end time: give --t-end or [simulate] t_end")
    samples = settings.pop("samples", None)
    streamed = str(args.output or "").lower().endswith(".nc")  # written as the run goes
    if samples and not streamed:
        from pfaff.core.memory import refuse_beyond
        from pfaff.integrate.pace import state_bytes

        refuse_beyond(
            samples * state_bytes(mf.system.n, mf.system.n_constraints),
            f"--samples {samples}",
            "report fewer times",
        )
    with warnings.catch_warnings():  # (the sets are reported below, not as a Python warning)
        warnings.simplefilter("ignore", RedundancyWarning)
        stage("deriving and compiling")
        model = mf.compile()
        t_eval = None if args.steps else _times(model, t_end, samples)
        stage("simulating")
        if verbose():
            settings.setdefault("progress", True)
        start = time.perf_counter()
        if streamed and getattr(model, "contacts", None) is None:
            settings["output"] = args.output  # (a run with contacts is written at the end)
        traj = simulate(model, mf.q0, mf.qd0, (0.0, t_end), t_eval=t_eval, **settings)
        wall = time.perf_counter() - start
    rep = _run_report(mf, traj, wall)
    rep["redundant_rows"] = int(np.max(traj.redundant_rows, initial=0))
    rep["redundant_sets"] = _run_redundancy(model, traj)
    stage("writing")
    if args.output:
        if traj.output is None:
            suffix = args.output.rsplit(".", 1)[-1].lower()
            (traj.to_netcdf if suffix == "nc" else traj.to_csv)(args.output)
        rep["output"] = args.output
    if args.plot:
        traj.plot(args.plot)
        rep["plot"] = args.plot
    if args.animate:
        traj.animate(args.animate, frames=args.frames)
        rep["animate"] = args.animate
    if args.json:
        print(dumps(rep))
    else:
        print(_run_text(rep))
    return 0 if traj.status == "success" else 3


def _times(model: Any, t_end: float, samples: int | None) -> np.ndarray:
    """The reported times: ``samples`` (the flag's or the file's) equally spaced, else
    :data:`REPORTED`, fewer when a family's states would not fit (:func:`reported_times`)."""
    from pfaff.cli.simdemo import reported_times

    if samples is not None:
        return np.linspace(0.0, t_end, samples)
    return reported_times(t_end, model.n, model.m, REPORTED)


def _run_report(mf: Any, traj: Any, wall: float) -> dict:
    """The demos' run summary (:func:`pfaff.cli.simdemo._summary`) with the file's model name,
    the final state and the largest constraint residual of either level."""
    from pfaff.cli.simdemo import _summary

    k = len(traj.t)
    rep = {"model": mf.name, **_summary(traj, wall)}
    rep.update(
        coordinates=list(traj.coordinate_names),
        q_final=traj.q[-1].tolist() if k else None,
        qd_final=traj.qd[-1].tolist() if k else None,
        multipliers_final=traj.multipliers[-1].tolist() if k else None,
        multiplier_names=list(traj.multiplier_names),
        energy_initial=float(traj.energy[0]) if k else None,
        energy_final=float(traj.energy[-1]) if k else None,
        max_constraint_residual=max(rep["max_position_residual"], rep["max_velocity_residual"]),
    )
    return rep


def _event_text(e: dict) -> str:
    """One event: its name, kind (for a contact's) and time."""
    kind = "" if e["kind"] == "event" else f" {e['kind']}"
    return f"{e['name']}{kind} at t = {e['t']:.10g}"


def _run_text(rep: dict) -> str:
    lines = [
        f"{rep['model']}: {rep['method']} to t = {rep['t_end']} — {rep['status']} ({rep['message']})"
    ]
    if rep["q_final"] is not None:
        pairs = zip(rep["coordinates"], rep["q_final"], strict=True)
        lines.append("  q(t_end): " + ", ".join(f"{n} = {v:.10g}" for n, v in pairs))
        lines.append(
            f"  energy {rep['energy_initial']:.10g} -> {rep['energy_final']:.10g}, work of the "
            f"applied forces {rep['nc_work']:.6g}, energy balance error "
            f"{rep['energy_balance_error']:.2e}, max constraint residual "
            f"{rep['max_constraint_residual']:.2e}"
        )
    if rep.get("events"):
        lines.append("  events: " + ", ".join(map(_event_text, rep["events"][:10])))
        if len(rep["events"]) > 10:
            lines[-1] += f", ... ({len(rep['events'])} in all)"
        impacts = [e for e in rep["events"] if e["kind"] in ("impact", "rest")]
        if impacts:
            lines.append(
                f"  impacts: {len(impacts)}, work of their impulses {rep['impact_work']:.6g}"
            )
    s = rep["stats"]
    lines.append("  " + ", ".join(f"{k} {v}" for k, v in s.items() if isinstance(v, int)))
    lines += [f"  {x}" for x in _redundancy_lines(rep.get("redundant_sets", []))[1:]]
    for key in ("output", "plot", "animate"):
        if key in rep:
            lines.append(f"Wrote {rep[key]}")
    return "\n".join(lines)
