"""Benchmark: ``pfaff.fit`` against opty's direct collocation on opty's Vyasarayani pendulum.

The data are ``tests/data/vyasarayani_pendulum.csv`` (``tests/data/make_vyasarayani.py``, seed
20110411): ÿ₁ = −p sin y₁ with p = 10 from (π/6, 0), 5000 samples on [0, 50] s, noise 0.05 on the
angle and 0.1 on the rate. Both fit p and the initial angle and rate to the noisy angle alone by
least squares, both from the same guess of p (``--guess``, default 50; opty's example draws it
from [0, 100)):

``opty``
    ``opty.Problem`` on ẏ₁ = y₂, ẏ₂ = −p sin y₁ by the midpoint rule on the 5000 nodes, the
    objective h Σ (y₁ − y₁,measured)² and its gradient, solved by IPOPT (through cyipopt) from the
    measured angle and rate as the guess of the trajectories.
``pfaff``
    ``pfaff.damped_pendulum`` with m = l = 1, c = 0 (p = g), ``pfaff.fit`` of g, ``q0.theta`` and
    ``qd0.theta`` (rtol 1e-8, atol 1e-12) by single shooting with exact sensitivities, the guess
    carried through windows of growing length (0.5, 2, 10 and 50 s) to avoid the example's local
    minima.

Rows: ``build`` (opty's ``Problem``, which generates and compiles Cython code in a subprocess;
pfaff's ``equations().compile()``, served by its on-disk cache after the warm-up) and ``fit``
(opty's ``solve``; pfaff's windowed fit, whose first call also builds the sensitivity kernels:
every case runs once untimed first). CPU seconds of the process and its children
(``resource.getrusage``), the two tools interleaved ``--repeats`` times, medians, and the ratio
pfaff / opty. The estimates of p are printed with their relative difference (the issue's check:
≤ 1e-3) and the midpoint rule's expected lag p h²/6 (see ``tests/api/test_fit_vyasarayani.py``).
Without opty installed (``pip install -e ".[bench]"``; cyipopt builds against IPOPT, on Debian the
packages coinor-libipopt-dev, liblapack-dev, libblas-dev and pkg-config) only pfaff's rows run,
against the estimate recorded in that test. Run from the project root::

    python benchmarks/fit.py [--repeats 3] [--guess 50]
"""

from __future__ import annotations

import argparse
import importlib.util
import resource
from pathlib import Path
from types import ModuleType

import numpy as np

import pfaff


def _reference() -> ModuleType:
    """``tests/api/test_fit_vyasarayani.py``: the data's path, opty's recorded estimate and the
    windowed fit, kept in one place."""
    path = Path(__file__).parents[1] / "tests" / "api" / "test_fit_vyasarayani.py"
    spec = importlib.util.spec_from_file_location("test_fit_vyasarayani", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


REFERENCE = _reference()


def cpu() -> float:
    """User + system CPU seconds of this process and its finished children."""
    own, kids = (
        resource.getrusage(who) for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)
    )
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def opty_cases(t: np.ndarray, angle: np.ndarray, rate: np.ndarray, guess: float) -> dict:
    """``build`` and ``fit`` of opty; the fit returns (p, y₁(0), y₂(0))."""
    import sympy as sp
    from opty import Problem

    n, h = len(t), (t[-1] - t[0]) / (len(t) - 1)
    p, time = sp.symbols("p t")
    y1, y2 = (f(time) for f in sp.symbols("y1 y2", cls=sp.Function))
    eom = sp.Matrix([y1.diff(time) - y2, y2.diff(time) + p * sp.sin(y1)])

    def objective(x: np.ndarray) -> float:
        return float(h * np.sum((x[:n] - angle) ** 2))

    def gradient(x: np.ndarray) -> np.ndarray:
        g = np.zeros_like(x)
        g[:n] = 2 * h * (x[:n] - angle)
        return g

    def build():
        prob = Problem(
            objective, gradient, eom, (y1, y2), n, h, time_symbol=time,
            integration_method="midpoint",
        )  # fmt: skip
        prob.add_option("print_level", 0)
        return prob

    problem = build()

    def fit():
        x, info = problem.solve(np.concatenate((angle, rate, [guess])))
        if info["status"] != 0:
            raise RuntimeError(f"opty/IPOPT did not converge: {info['status_msg']!r}")
        return float(x[-1]), float(x[0]), float(x[n])

    return {"build": build, "fit": fit}


def pfaff_cases(t: np.ndarray, angle: np.ndarray, guess: float) -> dict:
    """``build`` and ``fit`` of pfaff (the test's windowed fit); the fit returns (p, θ(0), θ̇(0))."""
    values = {"m": 1.0, "l": 1.0, "g": guess, "c": 0.0}

    def build():
        return pfaff.models.damped_pendulum().equations().compile(values)

    model = build()

    def fit():
        res = REFERENCE.fit_in_windows(model, t, angle, guess)
        if res.status != "success":
            raise RuntimeError(f"pfaff.fit did not converge: {res.message}")
        est = res.estimates
        return est["g"], est["q0.theta"], est["qd0.theta"]

    return {"build": build, "fit": fit}


def measure(tools: dict, repeats: int) -> tuple[dict, dict]:
    """Median CPU seconds per (tool, case), interleaved, and each tool's fit result."""
    results = {tool: cases["fit"]() for tool, cases in tools.items()}  # warm-up, untimed
    times: dict = {(tool, case): [] for tool, cases in tools.items() for case in cases}
    for _ in range(repeats):
        for case in ("build", "fit"):
            for tool, cases in tools.items():
                start = cpu()
                cases[case]()
                times[tool, case].append(cpu() - start)
    return {key: float(np.median(v)) for key, v in times.items()}, results


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--guess", type=float, default=50.0, help="the starting guess of p")
    args = ap.parse_args()
    t, angle, rate = np.loadtxt(REFERENCE.DATA, delimiter=",", skiprows=1).T
    tools = {}
    try:
        import opty

        tools["opty"] = opty_cases(t, angle, rate, args.guess)
        print(f"opty {opty.__version__}")
    except ImportError:
        print('opty is not installed (pip install -e ".[bench]"): pfaff only')
    tools["pfaff"] = pfaff_cases(t, angle, args.guess)
    med, results = measure(tools, args.repeats)

    h = (t[-1] - t[0]) / (len(t) - 1)
    print(f"\n{len(t)} samples, guess p = {args.guess:g}, CPU s (process + children), medians")
    print(f"{'case':<8}{'opty':>10}{'pfaff':>10}{'pfaff/opty':>12}")
    for case in ("build", "fit"):
        o = med.get(("opty", case), np.nan)
        f = med["pfaff", case]
        print(f"{case:<8}{o:>10.3f}{f:>10.3f}{f / o:>12.2f}")
    reference = results["opty"][0] if "opty" in results else REFERENCE.OPTY_P
    print(f"\n{'tool':<8}{'p':>14}{'y1(0)':>12}{'y2(0)':>12}")
    for tool, (p, a0, r0) in results.items():
        print(f"{tool:<8}{p:>14.9f}{a0:>12.7f}{r0:>12.7f}")
    p = results["pfaff"][0]
    source = "this run" if "opty" in results else "recorded"
    print(f"\nopty ({source}) / pfaff − 1 = {reference / p - 1:.3e} (check: |.| ≤ 1e-3)")
    print(f"the midpoint rule's lag p h²/6 = {p * h**2 / 6:.3e}")
    if "opty" in results:
        print(f"opty this run / recorded − 1 = {results['opty'][0] / REFERENCE.OPTY_P - 1:.1e}")


if __name__ == "__main__":
    main()
