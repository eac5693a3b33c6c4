"""Command-line interface.

``pfaff demo ring --particles N [--force F] [--json] [--plot FILE]`` derives and solves the seed's
ring; ``--simulate --t-end T [--method M] [--output traj.nc|.csv]`` integrates it in time, as does
``pfaff demo pendulum --simulate`` for the Cartesian pendulum.

Every outcome is one line on stderr and an exit code: 0 success, 2 a usage error or an error of
the model, its values or a file (checked before any computation where possible), 3 a simulation
that failed or was interrupted (its partial outputs written), 130 Ctrl-C before that, 1 anything
unexpected (``--debug`` shows its traceback).
"""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Sequence
from pathlib import Path

from pfaff.cli.argtypes import finite, not_an_input, positive, whole
from pfaff.cli.jsontext import dumps
from pfaff.cli.report import fail, guarded
from pfaff.cli.signals import forget, interrupted, interrupts, signalled, stage, swallowed
from pfaff.core.errors import OptionError

# the simulation options imply --simulate when given; these are their defaults
SIMULATION_DEFAULTS = {"t_end": 2.0, "method": "projection", "rtol": 1e-9, "atol": 1e-11}
OUTPUT_FORMATS = ("nc", "csv")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``pfaff`` command."""
    from pfaff import __version__

    p = argparse.ArgumentParser(
        prog="pfaff", description="Dynamics of constrained mechanical systems."
    )
    p.add_argument("--version", action="version", version=f"pfaff {__version__}")
    _debug_option(p, default=False)
    p.set_defaults(show_help=p.print_help)
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser("demo", help="run a built-in demonstration")
    demo.set_defaults(show_help=demo.print_help)
    _debug_option(demo)
    dsub = demo.add_subparsers(dest="demo", metavar="DEMO")
    ring = dsub.add_parser("ring", help="the seed's rolling ring of N particles")
    _debug_option(ring)
    ring.add_argument(
        "--particles",
        "-N",
        type=whole(2, "the ring needs at least 2 particles, got {v}"),
        default=6,
        help="number of particles (default 6)",
    )
    ring.add_argument(
        "--force", "-F", type=finite, default=2.0, help="push at the centre (default 2)"
    )
    ring.add_argument("--mass", type=positive, default=1.0, help="total mass M (default 1)")
    ring.add_argument("--radius", type=positive, default=0.5, help="radius r (default 0.5)")
    ring.add_argument("--theta-dot", type=finite, default=0.0, help="spin rate θ̇ (default 0)")
    ring.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    ring.add_argument(
        "--plot",
        metavar="FILE.png",
        help="write a figure of the ring and its multipliers (with --simulate: of the run); "
        "PNG, PDF, SVG, ... from the extension",
    )
    _simulation_options(ring)
    _animation_options(ring)
    pend = dsub.add_parser("pendulum", help="the Cartesian pendulum (x, y) with its rod constraint")
    _debug_option(pend)
    pend.add_argument("--mass", type=positive, default=1.0, help="bob mass m (default 1)")
    pend.add_argument("--length", type=positive, default=1.0, help="rod length L (default 1)")
    pend.add_argument("--gravity", type=finite, default=9.81, help="g (default 9.81)")
    pend.add_argument(
        "--angle", type=finite, default=90.0, help="release angle from the vertical, degrees"
    )
    pend.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    pend.add_argument(
        "--plot", metavar="FILE.png", help="write a figure of the run (implies --simulate)"
    )
    _simulation_options(pend)
    _body_demos(dsub)
    _bicycle_demo(dsub)
    from pfaff.cli.filecmd import add_parsers  # `pfaff equations` and `pfaff run` on a file

    add_parsers(sub, _debug_option)
    from pfaff.cli.sweepcmd import add_parser as add_sweep_parser  # `pfaff sweep`

    _debug_option(add_sweep_parser(sub))
    from pfaff.cli.fitcmd import add_parser as add_fit_parser  # `pfaff fit`

    add_fit_parser(sub, _debug_option)
    return p


def _body_demos(dsub: argparse._SubParsersAction) -> None:
    """``pfaff demo tumble|top|disk``: rigid bodies and attitude sets."""
    for name, text, t_end in (
        ("tumble", "the intermediate-axis flip of a torque-free body (ω, energy, |H|, MRP switches)", 40.0),
        ("top", "a heavy symmetric top on a steady precession", 3.0),
        ("disk", "a thin disk rolling without slip on a steady circle (contact forces)", 3.0),
    ):  # fmt: skip
        d = dsub.add_parser(name, help=text)
        _debug_option(d)
        if name != "disk":
            d.add_argument(
                "--attitude",
                choices=["euler", "quaternion", "mrp"],
                default="quaternion" if name == "tumble" else "euler",
                help="attitude coordinates of the body",
            )
        if name == "tumble":
            d.add_argument(
                "--sequence",
                help="Euler-angle sequence with --attitude euler (default 231, which this motion "
                "keeps clear of its singularity; 321 passes close to gimbal lock)",
            )
        d.add_argument(
            "--t-end", type=positive, default=t_end, help=f"end time (default {t_end:g})"
        )
        d.add_argument("--json", action="store_true", help="print one JSON object instead of text")
        d.add_argument("--plot", metavar="FILE.png", help="write a figure of the run")
        _animation_options(d)


def _bicycle_demo(dsub: argparse._SubParsersAction) -> None:
    """``pfaff demo bicycle``: the Whipple bicycle benchmark, linearized."""
    d = dsub.add_parser(
        "bicycle", help="the Whipple bicycle benchmark: eigenvalues, weave and capsize speeds"
    )
    _debug_option(d)
    d.add_argument("--speed", type=float, default=5.0, help="forward speed, m/s (default 5)")
    d.add_argument("--plot", metavar="FILE.png", help="write the root locus over 0-10 m/s")
    d.add_argument("--json", action="store_true", help="print one JSON object instead of text")


def run_bicycle(args: argparse.Namespace) -> int:
    """``pfaff demo bicycle``: 0 on success."""
    from pfaff.cli.bicycledemo import bicycle_report, format_bicycle

    if not math.isfinite(args.speed):
        raise OptionError(f"--speed must be finite; got {args.speed}")
    rep = bicycle_report(args.speed, args.plot)
    print(dumps(rep) if args.json else format_bicycle(rep))
    return 0


def run_body_demo(args: argparse.Namespace) -> int:
    """``pfaff demo tumble|top|disk``: 0 on success, 3 when the run failed (e.g. at gimbal lock)."""
    from pfaff.cli import bodydemo

    if args.demo == "tumble":
        rep, traj = bodydemo.tumble(args.attitude, t_end=args.t_end, sequence=args.sequence)
    elif args.demo == "top":
        rep, traj = bodydemo.top(args.attitude, t_end=args.t_end)
    else:
        rep, traj = bodydemo.disk(t_end=args.t_end)
    if args.plot:
        traj.plot(args.plot)
        rep["plot"] = args.plot
    _write_animation(traj, args, rep)
    if args.json:
        print(dumps(rep))
    else:
        print(bodydemo.format_body(rep))
        for key in ("plot", "animate"):
            if key in rep:
                print(f"Wrote {rep[key]}")
    return 0 if traj.status == "success" else 3


def _debug_option(p: argparse.ArgumentParser, default: object = argparse.SUPPRESS) -> None:
    """``--debug`` anywhere on the command line (a subcommand's copy keeps the global value)."""
    p.add_argument(
        "--debug",
        action="store_true",
        default=default,
        help="show the full traceback of an error (default: a one-line message)",
    )


def _simulation_options(p: argparse.ArgumentParser) -> None:
    from pfaff.integrate.simulation import METHODS

    g = p.add_argument_group("simulation (each option below implies --simulate)")
    g.add_argument("--simulate", action="store_true", help="integrate the motion in time")
    g.add_argument("--t-end", type=positive, help="end time (default 2)")
    g.add_argument("--method", choices=list(METHODS), help="integrator (default projection)")
    g.add_argument("--rtol", type=positive, help="relative tolerance (default 1e-9)")
    g.add_argument("--atol", type=positive, help="absolute tolerance (default 1e-11)")
    g.add_argument(
        "--output", metavar="FILE.nc|FILE.csv", help="write the trajectory (netCDF or CSV)"
    )


# ---- animations (Trajectory.animate): --animate/--frames of `demo ring` and the body demos
def _animation_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--animate",
        metavar="FILE.gif",
        help="write an animation of the run (GIF; MP4 where ffmpeg exists; implies --simulate)",
    )
    p.add_argument(
        "--frames",
        type=whole(1, "needs at least 1 frame, got {v}"),
        default=200,
        help="animation frames at most (default 200)",
    )


def _write_animation(traj, args: argparse.Namespace, rep: dict) -> None:
    if getattr(args, "animate", None):
        traj.animate(args.animate, frames=args.frames)
        rep["animate"] = args.animate


# ---- end of animations
def _resolve_simulation(args: argparse.Namespace) -> None:
    """Turn on --simulate when an option that only a simulation uses was given; fill defaults."""
    given = [
        k for k in (*SIMULATION_DEFAULTS, "output", "animate") if getattr(args, k, None) is not None
    ]
    if args.demo == "pendulum" and args.plot:  # the pendulum's only figure is of a run
        given.append("plot")
    args.simulate = args.simulate or bool(given)
    for k, v in SIMULATION_DEFAULTS.items():
        if getattr(args, k) is None:
            setattr(args, k, v)


def _check_file(flag: str, path: str, formats: Sequence[str], what: str) -> None:
    """Refuse an output file before any computation: unknown extension, missing folder."""
    suffix = Path(path).suffix.lstrip(".").lower()
    if suffix not in formats:
        ends = [f".{f}" for f in formats]
        allowed = " or ".join(ends) if len(ends) <= 2 else f"a {what} format ({', '.join(ends)})"
        raise OptionError(f"{flag} must end in {allowed}; got {path!r}")
    folder = Path(path).parent
    if not folder.is_dir():
        raise OptionError(f"{flag} {path!r}: the folder {str(folder)!r} does not exist")
    if Path(path).is_dir():
        raise OptionError(f"{flag} {path!r} is a folder; give a file name")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OptionError(f"{flag} {path!r}: the folder {str(folder)!r} is not writable")


def check_files(args: argparse.Namespace) -> None:
    """Check --output and --plot before anything is derived or computed (OptionError)."""
    if getattr(args, "output", None):
        _check_file("--output", args.output, OUTPUT_FORMATS, "trajectory")
    if getattr(args, "plot", None):
        from pfaff.results.figures import figure_formats

        _check_file("--plot", args.plot, figure_formats(), "figure")
    if getattr(args, "animate", None):  # also MP4 without ffmpeg
        from pfaff.results.animation import check_path

        _check_file("--animate", args.animate, ("gif", "mp4"), "animation")
        check_path(args.animate)
    _distinct_files(args)


def _distinct_files(args: argparse.Namespace) -> None:
    """Refuse two outputs of one command that are one file (the second would overwrite the
    first), and outputs that are devices or pipes (never replaced by a file)."""
    from pfaff.core.files import special_kind

    seen: dict[str, str] = {}
    for flag in ("output", "plot", "animate"):
        path = getattr(args, flag, None)
        if not path:
            continue
        kind = special_kind(Path(path))
        if kind is not None:
            raise OptionError(f"--{flag} {path!r} is {kind}, not a regular file: give a file name")
        real = os.path.realpath(path)
        if real in seen:
            raise OptionError(
                f"--{seen[real]} and --{flag} are the same file {path!r}: give each its own name"
            )
        seen[real] = flag
    not_an_input(args, [f for f in ("output", "plot", "animate") if getattr(args, f, None)])


def _write_outputs(traj, args: argparse.Namespace, rep: dict, units: dict[str, str]) -> None:
    if args.output:
        suffix = Path(args.output).suffix.lstrip(".").lower()
        if traj.output is None:  # (not streamed by simulate as the run went)
            (traj.to_netcdf if suffix == "nc" else traj.to_csv)(args.output)
        rep["output"] = args.output
    if args.plot:
        traj.plot(args.plot, units=units)
        rep["plot"] = args.plot
    _write_animation(traj, args, rep)


def run_simulation(args: argparse.Namespace) -> int:
    """Run ``pfaff demo ring|pendulum --simulate``: 0 on success, 3 when failed or interrupted
    (what was computed is written and reported all the same)."""
    from pfaff.cli.simdemo import (
        format_simulation,
        pendulum_simulation,
        ring_simulation,
        simulation_units,
    )

    opts = {"t_end": args.t_end, "method": args.method, "rtol": args.rtol, "atol": args.atol}
    if str(args.output or "").lower().endswith(".nc"):
        opts["output"] = args.output  # each reported state written as the run goes
    if args.demo == "ring":
        rep, traj = ring_simulation(
            args.particles,
            force=args.force,
            mass=args.mass,
            radius=args.radius,
            theta_dot=args.theta_dot,
            opts=opts,
        )
    else:
        rep, traj = pendulum_simulation(
            mass=args.mass,
            length=args.length,
            gravity=args.gravity,
            angle_deg=args.angle,
            opts=opts,
        )
    _write_outputs(traj, args, rep, simulation_units(args.demo, traj))
    if args.json:
        print(dumps(rep))
    else:
        print(format_simulation(rep))
        for key in ("output", "plot", "animate"):
            if key in rep:
                print(f"Wrote {rep[key]}")
    return 0 if traj.status == "success" else 3


def run_ring(args: argparse.Namespace) -> int:
    """Run ``pfaff demo ring``."""
    from pfaff.cli.demo import format_report, ring_report

    if args.simulate:
        return run_simulation(args)
    stage("deriving and solving")
    rep = ring_report(
        args.particles,
        force=args.force,
        mass=args.mass,
        radius=args.radius,
        theta_dot=args.theta_dot,
    )
    if args.plot:
        from pfaff.results.ring_figure import plot_ring

        plot_ring(rep, args.plot)
        rep["plot"] = args.plot
    rep.pop("_arrays")
    if args.json:
        print(dumps(rep))
    else:
        print(format_report(rep))
        if args.plot:
            print(f"Figure written to {args.plot}")
    return 0


def run_pendulum(args: argparse.Namespace) -> int:
    """``pfaff demo pendulum`` without --simulate: the equations and the tension at release."""
    import math

    import numpy as np

    from pfaff import models

    eom = models.cartesian_pendulum().equations()
    model = eom.compile({"m": args.mass, "g": args.gravity, "L": args.length})
    a = math.radians(args.angle)
    q = np.array([args.length * math.sin(a), -args.length * math.cos(a)])
    qdd, lam = model.accelerations(0.0, q, np.zeros(2))
    rep = {
        "equations": [str(e) for e in eom.lagrange_equations],
        "constraint": str(eom.holonomic_constraints[0]),
        "q": q.tolist(),
        "qdd": qdd.tolist(),
        "multipliers": lam.tolist(),
        "tension": float(-2 * args.length * lam[0]),
        "tension_exact": args.mass * args.gravity * math.cos(a),
    }
    if args.json:
        print(dumps(rep))
    else:
        print("Cartesian pendulum, q = (x, y):")
        for e in rep["equations"]:
            print("  ", e)
        print(f"   constraint f = {rep['constraint']} = 0")
        print(f"At release ({args.angle:g}° from the vertical, at rest): q̈ = {rep['qdd']}")
        print(
            f"   λ = {rep['multipliers'][0]:.12g}, rod tension −2Lλ = {rep['tension']:.12g}"
            f"   (at rest: m g cos θ₀ = {rep['tension_exact']:.12g})"
        )
        print("Add --simulate --t-end T to integrate the motion.")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pfaff`` console script.

    Returns
    -------
    int
        The exit code: 0 success (or help shown), 1 an unexpected error (one line; ``--debug``
        shows the traceback), 2 a usage, model, value or file error, 3 a simulation that failed or
        was interrupted, 130 interrupted (Ctrl-C) before a simulation.
    """
    forget()
    try:  # from the start: the parser imports the stages (seconds), an interrupt there is one line
        with interrupts():
            code = _main(argv)
            if (lost := swallowed(code)) is not None:  # received, and dropped by a library
                return fail(*lost, False)
            return code
    except KeyboardInterrupt as e:  # (a command's own interrupts are reported by `guarded`)
        return fail(*interrupted(e), False)
    except Exception as e:
        if (stopped := signalled(e)) is None:  # an interrupt turned into another error, or a bug
            raise
        return fail(*stopped, False)
    finally:
        forget()  # (this command's signals are its own: none are left for a later one)


def _main(argv: Sequence[str] | None) -> int:
    """:func:`main` inside the interrupt path."""
    stage("starting")
    parser = build_parser()
    args = parser.parse_args(argv)
    debug = bool(getattr(args, "debug", False))
    if args.command is None or (args.command == "demo" and args.demo is None):
        args.show_help()  # bare `pfaff` or `pfaff demo`: the help
        return 0
    if args.command == "sweep":  # it reports its own errors and exit codes
        from pfaff.cli.sweepcmd import run as run_sweep

        return run_sweep(args)
    return guarded(lambda: _dispatch(args), debug)


def _dispatch(args: argparse.Namespace) -> int:
    """The command or demo ``args`` names (errors are turned into exit codes by the caller)."""
    if args.command in ("equations", "run"):
        from pfaff.cli.filecmd import run_equations, run_model

        check_files(args)
        return run_equations(args) if args.command == "equations" else run_model(args)
    if args.command == "fit":
        from pfaff.cli.fitcmd import run as run_fit

        check_files(args)
        return run_fit(args)
    if args.demo == "bicycle":
        check_files(args)
        return run_bicycle(args)
    if args.demo in ("tumble", "top", "disk"):
        check_files(args)
        return run_body_demo(args)
    _resolve_simulation(args)
    check_files(args)
    if args.demo == "ring":
        return run_ring(args)
    return run_simulation(args) if args.simulate else run_pendulum(args)
