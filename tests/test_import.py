"""What ``import pfaff`` loads: its table of names only (:mod:`pfaff.core.exports`), the stages
when a name is first used, and never the packages that only some uses need (a structural check
of issue 26's import time, not a timing)."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

import pfaff

HEAVY = ("sympy", "symengine", "numpy", "scipy")  # what the stages import


def _imported(code: str) -> set[str]:
    """Every module ``python -X importtime -c code`` reports, in a fresh interpreter."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    out = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", code],
        capture_output=True, text=True, env=env, timeout=300, check=True,
    )  # fmt: skip
    lines = [ln.split("|") for ln in out.stderr.splitlines() if ln.startswith("import time:")]
    return {parts[2].strip() for parts in lines if len(parts) == 3}


def test_import_pfaff_and_its_command_load_no_stage() -> None:
    """The ``pfaff`` command starts (and puts its interrupt path in place) before any stage."""
    modules = _imported("import pfaff, pfaff.cli")
    assert {"pfaff", "pfaff.cli", "pfaff.cli.main"} <= modules  # the report is read
    assert not [m for m in modules if m.split(".")[0] in HEAVY]


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_the_stages_leave_the_heavy_packages_for_later() -> None:
    modules = _imported("import pfaff; pfaff.System, pfaff.simulate, pfaff.models")
    assert {"pfaff.api.system", "sympy", "numpy"} <= modules  # the report is read
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


def _type_checking_names(path: Path) -> dict[str, str]:
    """name -> module of the imports under ``if TYPE_CHECKING:`` in a package's __init__."""
    names = {}
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING":
            for imp in node.body:
                assert isinstance(imp, ast.ImportFrom) and imp.module
                for alias in imp.names:
                    module = imp.module
                    names[alias.asname or alias.name] = (
                        f"{module}.{alias.name}" if module == "pfaff" else module
                    )
    return names


def test_the_lazy_table_is_what_type_checkers_see() -> None:
    table = pfaff._EXPORTS
    assert _type_checking_names(Path(pfaff.__file__)) == {
        k: (v if k != "sweep" else "pfaff.sweep") for k, v in table.items()
    }
    assert pfaff.__all__ == sorted(table) and set(table) <= set(dir(pfaff))
    with pytest.raises(AttributeError, match="no attribute 'simulte'"):
        pfaff.simulte  # noqa: B018


@pytest.mark.slow  # (it imports every stage: the fast suite's tests resolve the names anyway)
def test_every_public_name_resolves() -> None:
    """A module where the table says so, else the object its module defines."""
    table = pfaff._EXPORTS
    for name, where in table.items():
        value = getattr(pfaff, name)
        module = sys.modules[where]
        assert value is (module if where == f"pfaff.{name}" else getattr(module, name))
    assert callable(pfaff.sweep) and pfaff.sweep.__module__ == "pfaff.sweep.driver"


def test_no_public_function_shares_its_name_with_a_module_of_its_package() -> None:
    """A submodule's first import sets the package's attribute of its name: a lazily exported
    function of that name would turn into the module (pfaff.sweep, the one case, is imported
    with pfaff for it)."""
    sweep = sys.modules["pfaff.sweep"]  # (imported with pfaff)
    for package, table in ((pfaff, pfaff._EXPORTS), (sweep, sweep._EXPORTS)):
        folder = Path(package.__file__).parent
        modules = {p.stem for p in folder.glob("*.py")} | {
            p.name for p in folder.iterdir() if (p / "__init__.py").exists()
        }
        shared = {n for n in table if n in modules and table[n] != f"{package.__name__}.{n}"}
        assert shared <= ({"sweep"} if package is pfaff else set()), shared
