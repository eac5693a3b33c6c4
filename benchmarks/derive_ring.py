"""Benchmark: from a model to one numeric (q̈, λ) for the rolling ring of N particles.

The model is :func:`pfaff.models.rolling_ring` with a horizontal push ``F`` at the centre:
coordinates (x, θ_1 … θ_N), particle k of mass M/N at (x + r sin θ_k, r cos θ_k), holonomic
constraints x - r θ_1 = 0 and θ_{k+1} - θ_k - 2π/N = 0. The exact answer at any consistent state
is θ̈ = F/(2 M r) and, for the no-slip multiplier, λ_1 = -F/2.

For every N one table row is printed with the pfaff pipeline split into stages (seconds):

``build``
    ``pfaff.models.rolling_ring(N, force=True)``
``equations``
    ``System.equations()``
``matrices``
    first access of ``mass_matrix``, ``forcing`` and ``constraint_matrix``
``compile``
    ``EquationsOfMotion.compile({"M": 1, "r": 0.5, "F": 2})``
``accel``
    one ``NumericModel.accelerations`` call at the state of ``pfaff.models.ring_state``
``total``
    the sum of the above,

then θ̈ (= q̈[1]) and λ_1 with their absolute errors against F/(2Mr) and -F/2. For N <= --sympy-max
the same pipeline is run with SymPy's ``sympy.physics.mechanics.LagrangesMethod`` (Particles on
Points of a ReferenceFrame, ``Lagrangian``, ``hol_coneqs``, the push as a forcelist entry on the
centre point, ``form_lagranges_equations()``, then ``mass_matrix_full``/``forcing_full`` lambdified
and solved with ``numpy.linalg.solve`` — cheaper than the symbolic ``lm.rhs()``), timed from
building to the number, with the ratio sympy_total / pfaff_total. SymPy's LagrangesMethod stores
the negative of the constraint Jacobian (sympy issue #30215), so its λ is reported as is and only
|λ_1| is checked. The SymPy cache is cleared (and the garbage collector run) before every
measurement so that earlier sizes do not warm up later ones; both pipelines are run once, untimed,
at N = 2 first so that lazy imports are not charged to the first row.

The summary gives the slope of log(total) against log(N) for pfaff over N >= 256 (≈ 1 means linear
scaling) and checks the targets: N = 128 in <= 0.5 s, N = 4096 in <= 10 s.

Run (from the project root)::

    python benchmarks/derive_ring.py                     # N = 8 … 4096, SymPy up to N = 64
    python benchmarks/derive_ring.py --quick             # N <= 128, SymPy up to N = 16
    python benchmarks/derive_ring.py --sizes 16 256 --sympy-max 0 --json ring.json
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import sympy as sp
from numpy.typing import NDArray
from sympy.physics.mechanics import (
    LagrangesMethod,
    Lagrangian,
    Particle,
    Point,
    ReferenceFrame,
    dynamicsymbols,
)

import pfaff

DEFAULT_SIZES = (8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096)
QUICK_MAX_N = 128
QUICK_SYMPY_MAX = 16
SLOPE_MIN_N = 256
TARGETS = ((128, 0.5), (4096, 10.0))  # (N, max total seconds)

MASS, RADIUS, FORCE = 1.0, 0.5, 2.0
THETA, THETA_DOT = 0.3, 0.0
EXPECTED_THETA_DDOT = FORCE / (2 * MASS * RADIUS)
EXPECTED_LAMBDA1 = -FORCE / 2


@dataclass
class PfaffResult:
    """Stage times (s) and results of the pfaff pipeline for one N."""

    build: float
    equations: float
    matrices: float
    compile: float
    accel: float
    theta_ddot: float
    lambda1: float

    @property
    def total(self) -> float:
        return self.build + self.equations + self.matrices + self.compile + self.accel


@dataclass
class SympyResult:
    """Stage times (s) and results of the SymPy LagrangesMethod pipeline for one N."""

    build: float
    form: float
    matrices: float
    lambdify: float
    solve: float
    theta_ddot: float
    lambda1: float

    @property
    def total(self) -> float:
        return self.build + self.form + self.matrices + self.lambdify + self.solve


@dataclass
class Row:
    """One table row: pfaff always, SymPy when N <= --sympy-max."""

    n: int
    pfaff: PfaffResult
    sympy: SympyResult | None = None


def fresh() -> None:
    """Forget SymPy's cache and collect garbage so a measurement starts from a cold state."""
    sp.core.cache.clear_cache()
    gc.collect()


def state(n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The consistent state at which both pipelines are evaluated."""
    return pfaff.models.ring_state(n, radius=RADIUS, theta=THETA, theta_dot=THETA_DOT)


def measure_pfaff(n: int) -> PfaffResult:
    """Run and time the pfaff pipeline for the ring of ``n`` particles."""
    q, qd = state(n)
    fresh()
    clock = time.perf_counter
    t0 = clock()
    ring = pfaff.models.rolling_ring(n, force=True)
    t1 = clock()
    eom = ring.equations()
    t2 = clock()
    _ = (eom.mass_matrix, eom.forcing, eom.constraint_matrix)
    t3 = clock()
    model = eom.compile({"M": MASS, "r": RADIUS, "F": FORCE})
    t4 = clock()
    qdd, lam = model.accelerations(0.0, q, qd)
    t5 = clock()
    return PfaffResult(
        build=t1 - t0,
        equations=t2 - t1,
        matrices=t3 - t2,
        compile=t4 - t3,
        accel=t5 - t4,
        theta_ddot=float(qdd[1]),
        lambda1=float(lam[0]),
    )


def measure_sympy(n: int) -> SympyResult:
    """Run and time SymPy's LagrangesMethod on the same ring, up to one numeric (q̈, λ)."""
    q, qd = state(n)
    fresh()
    clock = time.perf_counter
    t0 = clock()
    M, r, F = sp.symbols("M r F")
    qs = dynamicsymbols(f"x theta1:{n + 1}")
    x, th = qs[0], qs[1:]
    frame = ReferenceFrame("A")
    origin = Point("O")
    origin.set_vel(frame, 0)
    particles = []
    for k in range(n):
        pos = (x + r * sp.sin(th[k])) * frame.x + r * sp.cos(th[k]) * frame.y
        particles.append(Particle(f"P{k + 1}", origin.locatenew(f"p{k + 1}", pos), M / n))
    centre = origin.locatenew("C", x * frame.x)
    lagrangian = Lagrangian(frame, *particles)
    coneqs = [x - r * th[0]] + [th[k + 1] - th[k] - 2 * sp.pi / n for k in range(n - 1)]
    lm = LagrangesMethod(
        lagrangian, qs, forcelist=[(centre, F * frame.x)], hol_coneqs=coneqs, frame=frame
    )
    t1 = clock()
    lm.form_lagranges_equations()
    t2 = clock()
    mass_full, forcing_full = lm.mass_matrix_full, lm.forcing_full
    t3 = clock()
    q_sym, u_sym = sp.symbols(f"q0:{n + 1}"), sp.symbols(f"u0:{n + 1}")
    # One top-down xreplace: q'(t) is matched whole before q(t) inside it.
    plain = {qi.diff(): ui for qi, ui in zip(qs, u_sym, strict=True)}
    plain.update(zip(qs, q_sym, strict=True))
    args = [q_sym, u_sym, (M, r, F)]
    f_mass = sp.lambdify(args, mass_full.xreplace(plain), "numpy")
    f_forcing = sp.lambdify(args, forcing_full.xreplace(plain), "numpy")
    t4 = clock()
    params = (MASS, RADIUS, FORCE)
    a = np.asarray(f_mass(q, qd, params), dtype=float)
    b = np.asarray(f_forcing(q, qd, params), dtype=float).ravel()
    sol = np.linalg.solve(a, b)  # [q̇ (n+1), q̈ (n+1), λ (n)]
    t5 = clock()
    nq = n + 1
    return SympyResult(
        build=t1 - t0,
        form=t2 - t1,
        matrices=t3 - t2,
        lambdify=t4 - t3,
        solve=t5 - t4,
        theta_ddot=float(sol[nq + 1]),
        lambda1=float(sol[2 * nq]),
    )


# ---------------------------------------------------------------------------------------- output
COLUMNS: tuple[tuple[str, int], ...] = (
    ("N", 5),
    ("build", 8),
    ("equations", 9),
    ("matrices", 8),
    ("compile", 8),
    ("accel", 8),
    ("total", 8),
    ("θ̈", 9),
    ("err θ̈", 8),
    ("λ₁", 9),
    ("err λ₁", 8),
    ("sympy tot", 9),
    ("sympy θ̈", 9),
    ("sympy λ₁", 9),
    ("ratio", 7),
)


def _cells(values: list[str]) -> str:
    return " ".join(v.rjust(w) for v, (_, w) in zip(values, COLUMNS, strict=True))


def header() -> str:
    head = _cells([name for name, _ in COLUMNS])
    return f"{head}\n{'-' * len(head)}"


def format_row(row: Row) -> str:
    p = row.pfaff
    cells = [
        str(row.n),
        f"{p.build:.4f}",
        f"{p.equations:.4f}",
        f"{p.matrices:.4f}",
        f"{p.compile:.4f}",
        f"{p.accel:.4f}",
        f"{p.total:.4f}",
        f"{p.theta_ddot:.6f}",
        f"{abs(p.theta_ddot - EXPECTED_THETA_DDOT):.1e}",
        f"{p.lambda1:.6f}",
        f"{abs(p.lambda1 - EXPECTED_LAMBDA1):.1e}",
    ]
    s = row.sympy
    if s is None:
        cells += ["-", "-", "-", "-"]
    else:
        cells += [
            f"{s.total:.3f}",
            f"{s.theta_ddot:.6f}",
            f"{s.lambda1:.6f}",
            f"{s.total / p.total:.0f}x",
        ]
    return _cells(cells)


def pfaff_slope(rows: list[Row], min_n: int = SLOPE_MIN_N) -> float | None:
    """Least-squares slope of log(total) vs log(N) for pfaff over N >= min_n (None: < 2 sizes)."""
    pts = [(r.n, r.pfaff.total) for r in rows if r.n >= min_n]
    if len(pts) < 2:
        return None
    ns, ts = np.array(pts, dtype=float).T
    return float(np.polyfit(np.log(ns), np.log(ts), 1)[0])


def target_checks(rows: list[Row]) -> list[dict[str, object]]:
    """The time targets, each with the measured total and whether it holds (None: not measured)."""
    by_n = {r.n: r.pfaff.total for r in rows}
    out: list[dict[str, object]] = []
    for n, limit in TARGETS:
        total = by_n.get(n)
        out.append(
            {
                "n": n,
                "limit": limit,
                "total": total,
                "ok": None if total is None else total <= limit,
            }
        )
    return out


def accuracy_problems(rows: list[Row], tol: float = 1e-8) -> list[str]:
    """Rows whose θ̈ or λ_1 (|λ_1| for SymPy) miss the exact values by more than ``tol``."""
    bad = []
    for r in rows:
        p = r.pfaff
        if abs(p.theta_ddot - EXPECTED_THETA_DDOT) > tol or abs(p.lambda1 - EXPECTED_LAMBDA1) > tol:
            bad.append(f"pfaff N={r.n}")
        s = r.sympy
        if s is not None and (
            abs(s.theta_ddot - EXPECTED_THETA_DDOT) > tol
            or abs(abs(s.lambda1) - abs(EXPECTED_LAMBDA1)) > tol
        ):
            bad.append(f"sympy N={r.n}")
    return bad


def summary(rows: list[Row]) -> list[str]:
    lines = []
    slope = pfaff_slope(rows)
    slope_txt = f"n/a (needs two sizes >= {SLOPE_MIN_N})" if slope is None else f"{slope:.3f}"
    lines.append(f"pfaff slope of log(total) vs log(N) over N >= {SLOPE_MIN_N}: {slope_txt}")
    for chk in target_checks(rows):
        if chk["ok"] is None:
            verdict = "not measured"
        else:
            verdict = f"{chk['total']:.3f} s -> {'OK' if chk['ok'] else 'MISSED'}"
        lines.append(f"target N={chk['n']} total <= {chk['limit']} s: {verdict}")
    bad = accuracy_problems(rows)
    lines.append(
        "accuracy (|err| <= 1e-8): " + ("all OK" if not bad else "FAILED " + ", ".join(bad))
    )
    return lines


def row_to_json(row: Row) -> dict[str, object]:
    p = row.pfaff
    out: dict[str, object] = {
        "n": row.n,
        "pfaff": {
            **asdict(p),
            "total": p.total,
            "theta_ddot_error": abs(p.theta_ddot - EXPECTED_THETA_DDOT),
            "lambda1_error": abs(p.lambda1 - EXPECTED_LAMBDA1),
        },
        "sympy": None,
        "ratio": None,
    }
    if row.sympy is not None:
        s = row.sympy
        out["sympy"] = {
            **asdict(s),
            "total": s.total,
            "theta_ddot_error": abs(s.theta_ddot - EXPECTED_THETA_DDOT),
            "abs_lambda1_error": abs(abs(s.lambda1) - abs(EXPECTED_LAMBDA1)),
        }
        out["ratio"] = s.total / p.total
    return out


def write_json(path: Path, rows: list[Row]) -> None:
    """Write rows and summary as JSON atomically (temp file in the same dir, then os.replace)."""
    slope = pfaff_slope(rows)
    doc = {
        "benchmark": "derive_ring",
        "parameters": {"M": MASS, "r": RADIUS, "F": FORCE, "theta": THETA, "theta_dot": THETA_DOT},
        "expected": {"theta_ddot": EXPECTED_THETA_DDOT, "lambda1": EXPECTED_LAMBDA1},
        "versions": {
            "python": platform.python_version(),
            "pfaff": getattr(pfaff, "__version__", "?"),
            "sympy": sp.__version__,
            "numpy": np.__version__,
        },
        "rows": [row_to_json(r) for r in rows],
        "slope": {"min_n": SLOPE_MIN_N, "value": slope},
        "targets": target_checks(rows),
    }
    path = path.resolve()
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=2, allow_nan=False)
            fh.write("\n")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(
        description="Time pfaff (and SymPy's LagrangesMethod) from the rolling ring to (q̈, λ)."
    )
    ap.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=list(DEFAULT_SIZES),
        metavar="N",
        help="numbers of particles (default: %(default)s)",
    )
    ap.add_argument(
        "--sympy-max",
        type=int,
        default=64,
        metavar="N",
        help="run the SymPy baseline for N <= this (default: %(default)s; 0 disables it)",
    )
    ap.add_argument(
        "--quick",
        action="store_true",
        help=f"only N <= {QUICK_MAX_N}, SymPy only up to N = {QUICK_SYMPY_MAX}",
    )
    ap.add_argument("--json", type=Path, metavar="FILE", help="also write the rows as JSON")
    args = ap.parse_args(argv)
    if any(n < 2 for n in args.sizes):
        ap.error("--sizes: every N must be >= 2")
    args.sizes = sorted(set(args.sizes))
    if args.quick:
        args.sizes = [n for n in args.sizes if n <= QUICK_MAX_N]
        args.sympy_max = min(args.sympy_max, QUICK_SYMPY_MAX)
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    print(
        f"rolling ring, push F at the centre: M={MASS}, r={RADIUS}, F={FORCE}, θ={THETA}, "
        f"θ̇={THETA_DOT}; expected θ̈ = F/(2Mr) = {EXPECTED_THETA_DDOT}, λ₁ = -F/2 = "
        f"{EXPECTED_LAMBDA1}"
    )
    print(
        f"times in s; SymPy LagrangesMethod baseline for N <= {args.sympy_max}; "
        f"ratio = sympy total / pfaff total; python {platform.python_version()}, "
        f"sympy {sp.__version__}, numpy {np.__version__}"
    )
    # Untimed warm-up of both pipelines so that lazy imports are not charged to the first row.
    measure_pfaff(2)
    if args.sympy_max >= 2:
        measure_sympy(2)
    print(header(), flush=True)
    rows: list[Row] = []
    for n in args.sizes:
        row = Row(n, measure_pfaff(n))
        if n <= args.sympy_max:
            row.sympy = measure_sympy(n)
        rows.append(row)
        print(format_row(row), flush=True)
    print()
    for line in summary(rows):
        print(line)
    if args.json is not None:
        write_json(args.json, rows)
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
