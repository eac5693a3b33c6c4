"""``pfaff sweep MODEL.toml --vary NAME=START:STOP:COUNT [...]``: a parameter sweep from the shell.

Wired into ``pfaff`` by :mod:`pfaff.cli.main` (``add_parser(subparsers)``, then ``run(args)``
for the ``sweep`` command); :func:`main` runs it on its own. Exit codes as the other commands: 0
when the sweep completed, even if some runs failed (they are listed in the summary), 2 for a
usage, model or file error, 1 for anything unexpected, 130 for Ctrl-C; the message on stderr.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pfaff.cli.argtypes import not_an_input, positive, whole
from pfaff.cli.jsontext import dumps
from pfaff.cli.report import guarded, one_line
from pfaff.core.errors import OptionError

HELP = "simulate a model file over a grid of parameter values and initial states (Dask)"


def _vary(text: str) -> tuple[str, np.ndarray]:
    from pfaff.sweep import parse_vary

    try:
        return parse_vary(text)
    except OptionError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``sweep`` command to the ``pfaff`` command's subparsers; returns its parser."""
    p = subparsers.add_parser("sweep", help=HELP, description=HELP)
    p.add_argument("model", metavar="MODEL.toml", help="the model file")
    p.add_argument(
        "--vary",
        metavar="NAME=START:STOP:COUNT",
        type=_vary,
        action="append",
        required=True,
        help="a parameter (L=0.5:2:16), an initial coordinate (q0.theta=0:1:11) or speed "
        "(qd0.theta=...): COUNT values from START to STOP included; repeat for a grid",
    )
    p.add_argument("--t-end", type=positive, help="end time (default: the file's [simulate] t_end)")
    p.add_argument("--samples", type=whole(2), help="reported times per run (default 201)")
    p.add_argument("--output", metavar="FILE.nc", help="write the results as netCDF")
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a running Dask scheduler (tcp://host:8786); default: a local cluster of "
        "processes; 'synchronous': in this process",
    )
    p.add_argument("--workers", type=whole(1), help="local cluster size (default: the CPUs)")
    p.add_argument(
        "--run-timeout",
        type=positive,
        metavar="SECONDS",
        help="wall-clock seconds one run may take; a run over it is marked 'timeout' and the "
        "sweep goes on (default: no limit)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object (the summary)")
    return p


def run(args: argparse.Namespace) -> int:
    """Run the ``sweep`` command; its exit code (errors: one line on stderr, as every command)."""
    return guarded(lambda: _sweep(args), bool(getattr(args, "debug", False)))


def _sweep(args: argparse.Namespace) -> int:
    from pfaff.sweep import summary, sweep, write_netcdf

    vary: dict[str, np.ndarray] = {}
    for name, values in args.vary:
        if name in vary:
            raise OptionError(f"--vary {name} is given twice")
        vary[name] = values
    if args.output is not None:
        out = Path(args.output)
        if out.suffix.lower() != ".nc":
            raise OptionError(f"--output must be a netCDF file (.nc), got {args.output!r}")
        if not out.parent.is_dir() and str(out.parent):
            raise OptionError(f"--output: folder {str(out.parent)!r} does not exist")
        not_an_input(args, ["output"])
    scheduler = args.scheduler
    start = time.perf_counter()
    ds = sweep(
        args.model,
        vary,
        t_end=args.t_end,
        samples=args.samples,
        scheduler=scheduler,
        workers=args.workers,
        run_timeout=args.run_timeout,
    )
    seconds = time.perf_counter() - start
    if args.output is not None:
        write_netcdf(ds, args.output)
    rep = summary(ds)
    rep |= {
        "model": ds.attrs["model"],
        "file": ds.attrs["file"],
        "t_end": ds.attrs["t_end"],
        "samples": ds.attrs["samples"],
        "workers": ds.attrs["workers"],
        "scheduler": ds.attrs["scheduler"],
        "seconds": round(seconds, 3),
        "output": args.output,
    }
    print(dumps(rep, indent=None) if args.json else _text(rep))
    if ds.attrs.get("status") == "interrupted":  # the runs done are written and reported
        print("pfaff: interrupted: the runs done are kept, the others marked", file=sys.stderr)
        return 3
    return 0


def _text(rep: dict[str, Any]) -> str:
    grid = " × ".join(f"{d} ({k})" for d, k in rep["dims"].items())
    lines = [
        f"sweep of {rep['model']!r} ({rep['file']}): {rep['runs']} runs over {grid}, "
        f"t_end = {rep['t_end']:g}, {rep['samples']} samples per run",
        f"{rep['succeeded']} succeeded, {rep['failed']} failed in {rep['seconds']:.2f} s "
        f"({rep['scheduler']}, {rep['workers']} worker{'s' if rep['workers'] != 1 else ''})",
    ]
    e, r = rep["max_energy_error"], rep["max_constraint_residual"]
    if e is not None:
        lines.append(f"largest energy error {e:.3g}, largest constraint residual {r:.3g}")
    for f in rep["failures"]:
        point = ", ".join(f"{k} = {v:g}" for k, v in f["point"].items())
        lines.append(f"  {f['status']} at {point}: {one_line(f['message'])}")
    if rep["failed"] > len(rep["failures"]):
        lines.append(f"  ... and {rep['failed'] - len(rep['failures'])} more (see `status`)")
    if rep["output"]:
        lines.append(f"wrote {rep['output']}")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``pfaff sweep`` on its own: parse ``argv`` (the arguments after ``sweep``) and run.

    Examples
    --------
    >>> main(["model.toml", "--vary", "L=1:2"])  # a usage error: the message on stderr
    2
    """
    parser = argparse.ArgumentParser(prog="pfaff")
    add_parser(parser.add_subparsers(dest="command"))
    try:
        args = parser.parse_args(["sweep", *(sys.argv[1:] if argv is None else argv)])
    except SystemExit as e:  # argparse has printed the usage error
        return int(e.code or 0)
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
