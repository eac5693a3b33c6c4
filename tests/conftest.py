"""The test session's settings (its own code cache folder) and shared fixtures."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def pytest_configure(config: object) -> None:
    """The on-disk code cache of the run in a folder of its own: the user's stays untouched,
    and tests after the first compile of a model take the cache's load path."""
    import os
    import tempfile

    os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="pfaff-test-cache-")


@pytest.fixture(scope="module")
def fourbar_example():
    """examples/fourbar_sympy.py, imported as a module (a fresh copy per test module)."""
    spec = importlib.util.spec_from_file_location("fourbar_sympy", EXAMPLES / "fourbar_sympy.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
