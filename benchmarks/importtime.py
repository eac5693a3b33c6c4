"""Benchmark: the time ``import pfaff`` takes, against importing SymPy and NumPy alone (issue 26).

``import pfaff`` imports only its table of names, the stages on first use: what is timed is
``import pfaff`` with the first use of ``pfaff.System`` and ``pfaff.simulate`` (:data:`CODE`).
Each measurement is a fresh interpreter (``python -X importtime -c ...``) reading the cumulative
microseconds Python reports for the top-level modules: those ``CODE`` imports for a row, ``sympy``
plus ``numpy`` for the baseline (what pfaff cannot avoid: its equations are SymPy, its numbers
NumPy). The rows and the baseline alternate, ``--runs`` times (default 5), and the table gives
the medians, the ratio to the baseline and pfaff's own share (row − baseline). Bytecode is
cached as for an installed package: ``PYTHONDONTWRITEBYTECODE`` is removed from the children's
environment, ``PYTHONPYCACHEPREFIX`` points to a temporary folder (no checkout is written to) and
one untimed import of each row comes first; the operating system's file cache is warm, so "cold"
means a new process, not a new disk. The machine's load average is printed: the
numbers are only comparable within one run.

Rows: ``pfaff`` (this checkout's ``src``) and, with ``--compare PATH``, the ``src`` of another
checkout (before/after). Under each row, the heavy packages that must load only when used
(Dask, xarray, matplotlib, ``scipy.integrate``, ``sympy.physics``) that it imported anyway.

Run (from the project root)::

    python benchmarks/importtime.py
    python benchmarks/importtime.py --runs 9 --compare ../main/src
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

LAZY = ("dask", "distributed", "xarray", "matplotlib", "scipy.integrate", "sympy.physics")
ROOT = Path(__file__).resolve().parents[1]
CODE = "import pfaff; pfaff.System, pfaff.simulate"  # a script's start: the stages it uses
_LINE = re.compile(r"import time:\s+\d+ \|\s+(\d+) \|( *)(\S+)")


_PYCACHE = tempfile.mkdtemp(prefix="pfaff-importtime-")


def importtime(code: str, src: Path | None) -> dict[str, int]:
    """Cumulative µs of every module ``code`` imports, in a fresh interpreter; under ``""``
    the sum over the top-level ones."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = _PYCACHE
    if src is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(src), env.get("PYTHONPATH", "")]).rstrip(
            os.pathsep
        )
    err = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", code],
        capture_output=True, text=True, env=env, check=True,
    ).stderr  # fmt: skip
    out: dict[str, int] = {"": 0}  # "": the sum over the top-level modules (depth 0)
    for line in err.splitlines():
        m = _LINE.match(line)
        if m:
            out[m.group(3)] = int(m.group(1))  # every module, nested or not
            out[""] += int(m.group(1)) if len(m.group(2)) == 1 else 0
    return out


def loaded(times: dict[str, int]) -> list[str]:
    """The packages of :data:`LAZY` among the imported modules."""
    return [p for p in LAZY if p in times]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5, help="interleaved runs (default 5)")
    ap.add_argument("--compare", type=Path, help="another checkout's src, timed alongside")
    args = ap.parse_args()
    rows = {"pfaff": ROOT / "src"}
    if args.compare is not None:
        rows[f"pfaff ({args.compare})"] = args.compare.resolve()
    importtime("import sympy, numpy", None)  # bytecode written once, untimed
    for src in rows.values():
        importtime(CODE, src)
    base: list[float] = []
    ms: dict[str, list[float]] = {name: [] for name in rows}
    heavy: dict[str, list[str]] = {}
    for _ in range(args.runs):
        b = importtime("import sympy, numpy", None)
        base.append(b[""] / 1e3)  # sympy and numpy, and what either imports
        for name, src in rows.items():
            t = importtime(CODE, src)
            ms[name].append(t[""] / 1e3)
            heavy[name] = loaded(t)
    b = statistics.median(base)
    print(f"import time, medians of {args.runs} fresh interpreters (ms, python -X importtime)")
    print(f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} CPUs")
    print(f"{'row':<40} {'ms':>8} {'ratio':>7} {'own ms':>8}  runs")
    print(f"{'baseline: sympy + numpy':<40} {b:8.0f} {1.0:7.2f} {0.0:8.0f}  "
          + " ".join(f"{x:.0f}" for x in base))  # fmt: skip
    for name, xs in ms.items():
        m = statistics.median(xs)
        print(f"{name:<40} {m:8.0f} {m / b:7.2f} {m - b:8.0f}  " + " ".join(f"{x:.0f}" for x in xs))
        print(f"{'':<40} loaded eagerly: {', '.join(heavy[name]) or 'none of ' + ', '.join(LAZY)}")


if __name__ == "__main__":
    main()
