"""``pfaff fit MODEL.toml data.csv --fit NAME=GUESS [...]``: identify parameters from a CSV file.

The data file has a header row; the column ``t`` holds the times and the columns named after
coordinates (or ``<coordinate>_dot`` for rates; the names of ``pfaff run --output run.csv``)
the measurements: all of those by default, or the ones ``--observe`` names. Every value is read
as a number (``float``), nothing else; a value that is not a finite number is refused with its
row and column. The model file gives the other parameters' values and the initial state
(``--fit q0.theta=0.5`` fits an entry of it). Exit codes as the other commands: 0 when the fit
converged, 3 when the optimizer stopped without converging, 2 for a usage, model, data or file
error.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from pfaff.cli.argtypes import positive
from pfaff.core.errors import OptionError, RedundancyWarning

HELP = "fit parameters (and initial values) of a model file to measured motion in a CSV file"
MAX_DATA_BYTES = 64 * 2**20  # the data file's size cap


def _guess(text: str) -> tuple[str, float]:
    """``NAME=VALUE`` with NAME a parameter or ``q0.<name>``/``qd0.<name>``, VALUE a number."""
    name, eq, value = text.partition("=")
    name = name.strip()
    kind, dot, coord = name.partition(".")
    plain = name.isidentifier() or (dot and kind in ("q0", "qd0") and coord.isidentifier())
    if not eq or not plain:
        raise argparse.ArgumentTypeError(
            f"bad --fit {text!r:.80}: expected NAME=GUESS (c=0.1, or q0.<coordinate>=0.5)"
        )
    try:
        v = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"bad --fit {text!r:.80}: GUESS must be a number"
        ) from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"bad --fit {text!r:.80}: GUESS must be finite")
    return name, v


def add_parser(subparsers: Any, common: Any) -> argparse.ArgumentParser:
    """Add the ``fit`` command; ``common(p)`` adds the shared options."""
    p = subparsers.add_parser("fit", help=HELP, description=HELP)
    p.add_argument("model", metavar="MODEL.toml", help="the model file")
    p.add_argument("data", metavar="data.csv", help="measurements: a header row, column t")
    p.add_argument(
        "--fit",
        metavar="NAME=GUESS",
        type=_guess,
        action="append",
        required=True,
        help="a parameter to fit and its initial guess (c=0.1), or an initial value "
        "(q0.theta=0.5, qd0.theta=0); repeat for each",
    )
    p.add_argument(
        "--observe",
        metavar="COLUMN",
        action="append",
        help="a data column to fit (a coordinate or <coordinate>_dot); default: all such columns",
    )
    p.add_argument("--rtol", type=positive, help="integrator relative tolerance (default 1e-9)")
    p.add_argument("--atol", type=positive, help="integrator absolute tolerance (default 1e-11)")
    p.add_argument("--plot", metavar="fit.png", help="write a figure of the data and the fit")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--max-bytes", type=int, default=None, help="raise the 1 MB model-file cap")
    common(p)
    return p


def read_data(path: str) -> tuple[list[str], np.ndarray]:
    """(column names, values (rows, columns)) of a CSV file with a header row; numbers only."""
    file = Path(path)
    if not file.is_file():
        raise OptionError(f"data file {path!r}: no such file")
    if file.stat().st_size > MAX_DATA_BYTES:
        raise OptionError(f"data file {path!r}: larger than {MAX_DATA_BYTES >> 20} MB")
    with file.open(newline="", encoding="utf-8") as fh:
        try:
            rows = list(csv.reader(fh))
        except (csv.Error, UnicodeDecodeError) as e:
            raise OptionError(f"data file {path!r}: not a CSV file ({e})") from None
    rows = [r for r in rows if any(cell.strip() for cell in r)]
    if len(rows) < 3:
        raise OptionError(f"data file {path!r}: needs a header row and at least 2 rows of data")
    header = [h.strip() for h in rows[0]]
    if len(set(header)) != len(header):
        raise OptionError(f"data file {path!r}: a column name repeats in the header")
    values = np.empty((len(rows) - 1, len(header)))
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise OptionError(
                f"data file {path!r}, row {i}: {len(row)} values for {len(header)} columns"
            )
        for j, cell in enumerate(row):
            try:
                v = float(cell)
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise OptionError(
                    f"data file {path!r}, row {i}, column {header[j]!r}: {cell!r:.40} is not a "
                    "finite number"
                ) from None
            values[i - 2, j] = v
    return header, values


def _columns(header: list[str], coords: list[str], observe: list[str] | None) -> list[str]:
    """The observed columns: ``observe``, or every column naming a coordinate or a rate."""
    if "t" not in header:
        raise OptionError("the data file has no column `t` (the measurement times)")
    known = coords + [f"{c}_dot" for c in coords]
    if observe:
        missing = [c for c in observe if c not in header]
        if missing:
            raise OptionError(
                f"--observe: no column {', '.join(map(repr, missing))} in the data file "
                f"(columns: {', '.join(header)})"
            )
        return list(observe)
    cols = [h for h in header if h in known]
    if not cols:
        raise OptionError(
            "no column of the data file names a coordinate or a rate "
            f"({', '.join(known)}); columns: {', '.join(header)}"
        )
    return cols


def run(args: argparse.Namespace) -> int:
    """Fit, print the estimates with their standard errors; 0 converged, 3 not."""
    from pfaff.api.fit import fit
    from pfaff.modelfile import load_model

    guesses = dict(args.fit)
    if len(guesses) != len(args.fit):
        raise OptionError("--fit names a value twice")
    kw = {} if args.max_bytes is None else {"max_bytes": args.max_bytes}
    mf = load_model(args.model, **kw)
    header, values = read_data(args.data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundancyWarning)
        model = mf.compile()
    cols = _columns(header, list(model.coordinate_names), args.observe)
    options = {k: getattr(args, k) for k in ("rtol", "atol") if getattr(args, k) is not None}
    t = values[:, header.index("t")]
    measured = values[:, [header.index(c) for c in cols]]
    res = fit(model, t, measured, guesses, cols, mf.q0, mf.qd0, **options)
    rep = {"model": mf.name, "data": args.data, "observed": cols, **res.to_dict()}
    if args.plot:
        res.plot(args.plot)
        rep["plot"] = args.plot
    if args.json:
        print(json.dumps(rep, indent=1))
    else:
        print(_text(rep))
    return 0 if res.status == "success" else 3


def _text(rep: dict) -> str:
    lines = [f"{rep['model']}: fit to {rep['data']} ({', '.join(rep['observed'])})"]
    width = max(len(k) for k in rep["estimates"])
    for k, v in rep["estimates"].items():
        lines.append(f"  {k:<{width}} = {v:.10g} ± {rep['standard_errors'][k]:.3g}")
    rms = ", ".join(f"{k} {v:.3g}" for k, v in rep["residual_rms"].items())
    lines.append(f"residual RMS: {rms}")
    lines.append(f"{rep['status']}: {rep['message']} ({rep['nfev']} runs)")
    return "\n".join(lines)
