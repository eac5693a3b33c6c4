"""Shared fixtures (the run's code cache folder is set in the top-level conftest.py)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def fourbar_example():
    """examples/fourbar_sympy.py, imported as a module (a fresh copy per test module)."""
    spec = importlib.util.spec_from_file_location("fourbar_sympy", EXAMPLES / "fourbar_sympy.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
