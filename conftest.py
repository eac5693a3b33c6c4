"""The test session's code cache: one folder of its own per run, for the tests and the doctests.

The user's ``$XDG_CACHE_HOME/pfaff`` stays untouched, and a model compiled once in the run is
loaded from the cache by every later test: the compile path runs first, the load path after. The
folder is made by the main process, shared with pytest-xdist's workers (a model compiled on one
worker is loaded on the others; entries are written atomically, so concurrent writers are safe)
and removed at the end of the run. Every test ends with ``XDG_CACHE_HOME`` set back to it, so a
test or doctest that changes it leaves no trace on the tests after it.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from collections.abc import Iterator

import pytest

# An environment may set PYTHONDONTWRITEBYTECODE (this machine's does): the test session writes
# bytecode anyway, so that pytest's rewritten test modules and pfaff's compiled modules are read
# back by the next run, by the other workers and by the CLI subprocesses the tests start, not
# compiled again by each (about 5 s of assertion rewriting per worker)
sys.dont_write_bytecode = False

_HOME = pytest.StashKey[str]()  # the run's cache home (XDG_CACHE_HOME)
_MADE = pytest.StashKey[bool]()  # made by this process (removed by it at the end)
_WORKER_KEY = "pfaff_cache_home"


def pytest_configure(config: pytest.Config) -> None:
    inherited = getattr(config, "workerinput", {}).get(_WORKER_KEY)
    home = inherited or tempfile.mkdtemp(prefix="pfaff-test-cache-")
    config.stash[_HOME] = home
    config.stash[_MADE] = inherited is None
    os.environ["XDG_CACHE_HOME"] = home
    if inherited is None:  # the main process, before xdist starts its workers
        _prepare_stepping_loop()


def _prepare_stepping_loop() -> None:
    """Compile the compiled stepping loop (numba) once, here, into numba's on-disk cache, so
    the workers load it instead of each compiling it at once on a cold machine (about 11 s of
    CPU each); likewise the compiled passes of long states (sin and cos, DOP853's sums, the
    multipliers' running sum: about 2.5 s). Without numba, or with ``PFAFF_LOOP=0``
    (``PFAFF_JIT=0``), nothing happens."""
    from pfaff.integrate.inplacejit import kernels
    from pfaff.integrate.loop import _kernel
    from pfaff.numeric.banded import _summer
    from pfaff.numeric.trigjit import compiled

    _kernel()
    compiled()
    kernels()
    _summer()


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node) -> None:  # pytest-xdist: a worker is being started
    node.workerinput[_WORKER_KEY] = node.config.stash[_HOME]


def pytest_unconfigure(config: pytest.Config) -> None:
    if config.stash.get(_MADE, False):
        shutil.rmtree(config.stash[_HOME], ignore_errors=True)


@pytest.fixture(autouse=True)
def _session_cache_home(pytestconfig: pytest.Config) -> Iterator[None]:
    """``XDG_CACHE_HOME`` back to the run's folder after the test (a doctest of
    ``pfaff.derive.cache`` deletes it; tests that set their own use monkeypatch)."""
    yield
    home = pytestconfig.stash[_HOME]
    if os.environ.get("XDG_CACHE_HOME") != home:
        os.environ["XDG_CACHE_HOME"] = home


# Doctests that derive a big model, run by the full suite only: (why, what covers their path fast)
SLOW_DOCTESTS = {
    "pfaff.models.bicycle.whipple_bicycle": (
        "the Whipple bicycle derived and linearized: about 2 s; the rolling disk's linearization "
        "(tests/derive/test_linearize.py) takes the same path in the fast suite"
    ),
    "pfaff.derive.compile_family.compile_structured": (
        "a family compiled from scratch: 0.6 s; tests/derive/test_families.py compiles families "
        "in the fast suite"
    ),
}


@pytest.hookimpl(tryfirst=True)  # before -m deselects
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if isinstance(item, pytest.DoctestItem) and item.name in SLOW_DOCTESTS:
            item.add_marker(pytest.mark.slow)
