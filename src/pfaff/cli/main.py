"""Command-line interface.

``pfaff demo ring --particles N [--force F] [--json] [--plot FILE]`` derives and solves the seed's
ring; ``--simulate --t-end T [--method M] [--output traj.nc|.csv]`` integrates it in time, as does
``pfaff demo pendulum --simulate`` for the Cartesian pendulum.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from pfaff.core.errors import PfaffError


def _positive_int(s: str) -> int:
    try:
        v = int(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {s!r}") from None
    if v < 2:
        raise argparse.ArgumentTypeError(f"the ring needs at least 2 particles, got {v}")
    return v


def _finite(s: str) -> float:
    try:
        v = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {s!r}") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {s!r}")
    return v


def _positive(s: str) -> float:
    v = _finite(s)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {s!r}")
    return v


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``pfaff`` command."""
    from pfaff import __version__

    p = argparse.ArgumentParser(
        prog="pfaff", description="Dynamics of constrained mechanical systems."
    )
    p.add_argument("--version", action="version", version=f"pfaff {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run a built-in demonstration")
    dsub = demo.add_subparsers(dest="demo", required=True)
    ring = dsub.add_parser("ring", help="the seed's rolling ring of N particles")
    ring.add_argument(
        "--particles", "-N", type=_positive_int, default=6, help="number of particles (default 6)"
    )
    ring.add_argument(
        "--force", "-F", type=_finite, default=2.0, help="push at the centre (default 2)"
    )
    ring.add_argument("--mass", type=_positive, default=1.0, help="total mass M (default 1)")
    ring.add_argument("--radius", type=_positive, default=0.5, help="radius r (default 0.5)")
    ring.add_argument("--theta-dot", type=_finite, default=0.0, help="spin rate θ̇ (default 0)")
    ring.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    ring.add_argument(
        "--plot",
        metavar="FILE.png",
        help="write a figure of the ring and its multipliers (with --simulate: of the run)",
    )
    _simulation_options(ring)
    pend = dsub.add_parser("pendulum", help="the Cartesian pendulum (x, y) with its rod constraint")
    pend.add_argument("--mass", type=_positive, default=1.0, help="bob mass m (default 1)")
    pend.add_argument("--length", type=_positive, default=1.0, help="rod length L (default 1)")
    pend.add_argument("--gravity", type=_finite, default=9.81, help="g (default 9.81)")
    pend.add_argument(
        "--angle", type=_finite, default=90.0, help="release angle from the vertical, degrees"
    )
    pend.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    pend.add_argument("--plot", metavar="FILE.png", help="write a figure of the run")
    _simulation_options(pend)
    return p


def _simulation_options(p: argparse.ArgumentParser) -> None:
    from pfaff.integrate.simulation import METHODS

    g = p.add_argument_group("simulation")
    g.add_argument("--simulate", action="store_true", help="integrate the motion in time")
    g.add_argument("--t-end", type=_positive, default=2.0, help="end time (default 2)")
    g.add_argument("--method", choices=list(METHODS), default="projection", help="integrator")
    g.add_argument("--rtol", type=_positive, default=1e-9, help="relative tolerance")
    g.add_argument("--atol", type=_positive, default=1e-11, help="absolute tolerance")
    g.add_argument(
        "--output", metavar="FILE.nc|FILE.csv", help="write the trajectory (netCDF or CSV)"
    )


def _write_outputs(traj, args: argparse.Namespace, rep: dict) -> None:
    if args.output:
        suffix = args.output.rsplit(".", 1)[-1].lower()
        (traj.to_netcdf if suffix == "nc" else traj.to_csv)(args.output)
        rep["output"] = args.output
    if args.plot:
        traj.plot(args.plot)
        rep["plot"] = args.plot


def run_simulation(args: argparse.Namespace) -> int:
    """Run ``pfaff demo ring|pendulum --simulate``."""
    from pfaff.cli.simdemo import format_simulation, pendulum_simulation, ring_simulation

    if args.output and args.output.rsplit(".", 1)[-1].lower() not in ("nc", "csv"):
        raise PfaffError(f"--output must end in .nc or .csv; got {args.output!r}")
    opts = {"t_end": args.t_end, "method": args.method, "rtol": args.rtol, "atol": args.atol}
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
    _write_outputs(traj, args, rep)
    if args.json:
        print(json.dumps(rep, indent=1))
    else:
        print(format_simulation(rep))
        for key in ("output", "plot"):
            if key in rep:
                print(f"Wrote {rep[key]}")
    return 0 if traj.status == "success" else 3


def run_ring(args: argparse.Namespace) -> int:
    """Run ``pfaff demo ring``."""
    from pfaff.cli.demo import format_report, ring_report

    if args.simulate:
        return run_simulation(args)

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
        print(json.dumps(rep, indent=1))
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
        print(json.dumps(rep, indent=1))
    else:
        print("Cartesian pendulum, q = (x, y):")
        for e in rep["equations"]:
            print("  ", e)
        print(f"   constraint f = {rep['constraint']} = 0")
        print(f"At release ({args.angle:g}° from the vertical, at rest): q̈ = {rep['qdd']}")
        print(f"   λ = {rep['multipliers'][0]:.12g}, rod tension −2Lλ = {rep['tension']:.12g}")
        print("Add --simulate --t-end T to integrate the motion.")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pfaff`` console script."""
    args = build_parser().parse_args(argv)
    try:
        if args.command == "demo" and args.demo == "ring":
            return run_ring(args)
        if args.command == "demo" and args.demo == "pendulum":
            return run_simulation(args) if args.simulate else run_pendulum(args)
    except (PfaffError, OSError) as e:
        print(f"pfaff: error: {e}", file=sys.stderr)
        return 2
    return 1
