"""Command-line interface: ``pfaff demo ring --particles N [--force F] [--json] [--plot FILE]``."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from .errors import PfaffError


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
    from . import __version__

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
        "--plot", metavar="FILE.png", help="write a figure of the ring and its multipliers"
    )
    return p


def run_ring(args: argparse.Namespace) -> int:
    """Run ``pfaff demo ring``."""
    from .demo import format_report, ring_report

    rep = ring_report(
        args.particles,
        force=args.force,
        mass=args.mass,
        radius=args.radius,
        theta_dot=args.theta_dot,
    )
    if args.plot:
        from .plot import plot_ring

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


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pfaff`` console script."""
    args = build_parser().parse_args(argv)
    try:
        if args.command == "demo" and args.demo == "ring":
            return run_ring(args)
    except (PfaffError, OSError) as e:
        print(f"pfaff: error: {e}", file=sys.stderr)
        return 2
    return 1


if __name__ == "__main__":
    sys.exit(main())
