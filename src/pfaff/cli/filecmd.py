"""``pfaff equations MODEL.toml`` and ``pfaff run MODEL.toml``: the CLI on a model file."""

from __future__ import annotations

import argparse
import time
import warnings
from typing import Any

import numpy as np

from pfaff.cli.argtypes import positive, whole
from pfaff.cli.jsontext import dumps
from pfaff.cli.signals import stage, verbose
from pfaff.core.errors import RedundancyWarning

RUN_FLAGS = ("t_end", "method", "rtol", "atol")


def add_parsers(sub: argparse._SubParsersAction, common: Any) -> None:
    """The ``equations`` and ``run`` subcommands; ``common(p)`` adds the shared options."""
    from pfaff.integrate.simulation import METHODS

    eq = sub.add_parser("equations", help="derive and print the equations of a model file")
    eq.add_argument("model", metavar="MODEL.toml", help="the model file")
    eq.add_argument("--latex", action="store_true", help="print LaTeX instead of text")
    eq.add_argument("--json", action="store_true", help="print one JSON object")
    eq.add_argument("--max-bytes", type=whole(1), default=None, help="raise the 1 MB file-size cap")
    common(eq)
    run = sub.add_parser("run", help="simulate a model file")
    run.add_argument("model", metavar="MODEL.toml", help="the model file")
    run.add_argument("--t-end", type=positive, help="end time (default: the file's [simulate])")
    run.add_argument("--method", choices=list(METHODS), help="integrator (default: the file's)")
    run.add_argument("--rtol", type=positive, help="relative tolerance")
    run.add_argument("--atol", type=positive, help="absolute tolerance")
    run.add_argument("--samples", type=whole(2), help="report this many equally spaced times")
    run.add_argument("--output", metavar="run.nc|run.csv", help="write the trajectory")
    run.add_argument("--plot", metavar="run.png", help="write a figure of the run")
    run.add_argument("--animate", metavar="run.gif", help="write an animation of the run")
    run.add_argument(
        "--frames",
        type=whole(1, "needs at least 1 frame, got {v}"),
        default=200,
        help="animation frames (default 200)",
    )
    run.add_argument("--json", action="store_true", help="print one JSON object")
    run.add_argument(
        "--max-bytes", type=whole(1), default=None, help="raise the 1 MB file-size cap"
    )
    common(run)


def _load(args: argparse.Namespace) -> Any:
    from pfaff.modelfile import load_model

    kw = {} if args.max_bytes is None else {"max_bytes": args.max_bytes}
    stage("loading")
    return load_model(args.model, **kw)


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
    if samples:
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
        t_eval = np.linspace(0.0, t_end, samples) if samples else None
        stage("simulating")
        if verbose():
            settings.setdefault("progress", True)
        start = time.perf_counter()
        traj = simulate(model, mf.q0, mf.qd0, (0.0, t_end), t_eval=t_eval, **settings)
        wall = time.perf_counter() - start
    rep = _run_report(mf, traj, wall)
    rep["redundant_rows"] = int(np.max(traj.redundant_rows, initial=0))
    rep["redundant_sets"] = _run_redundancy(model, traj)
    stage("writing")
    if args.output:
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
