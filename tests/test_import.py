"""What ``import pfaff`` loads: SymPy, SymEngine, NumPy and SciPy's linear algebra, and not the
packages that only some uses need (a structural check of issue 26's import time, not a timing)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

LAZY = ("dask", "distributed", "xarray", "matplotlib", "scipy.integrate", "sympy.physics")


def _imported(code: str) -> set[str]:
    """Every module ``python -X importtime -c code`` reports, in a fresh interpreter."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    out = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", code],
        capture_output=True, text=True, env=env, timeout=300, check=True,
    )  # fmt: skip
    lines = [ln.split("|") for ln in out.stderr.splitlines() if ln.startswith("import time:")]
    return {parts[2].strip() for parts in lines if len(parts) == 3}


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_import_pfaff_leaves_the_heavy_packages_for_later() -> None:
    modules = _imported("import pfaff")
    assert {"pfaff", "sympy", "numpy"} <= modules  # the report is read
    assert not [m for m in modules if m.split(".")[0] in ("dask", "distributed", "xarray")]
    assert not [m for m in modules if m == "matplotlib" or m.startswith("matplotlib.")]
    assert "scipy.integrate" not in modules and "scipy.optimize" not in modules
    assert "sympy.physics" not in modules  # its units package alone is a tenth of the time


@pytest.mark.slow
@pytest.mark.parametrize(
    ("code", "package"),
    [
        ("pfaff.simulate(pfaff.models.pendulum().equations().compile("
         "{'m': 1, 'g': 1, 'L': 1}), [0.1], [0.0], (0, 0.1))", "scipy.integrate"),
        ("pfaff.models.pendulum().equations().latex()", "sympy.physics"),
    ],
)  # fmt: skip
def test_used_packages_load_when_used(code: str, package: str) -> None:
    assert package in _imported(f"import pfaff\n{code}")
