"""The test session's settings (its own code cache folder)."""

from __future__ import annotations


def pytest_configure(config: object) -> None:
    """The on-disk code cache of the run in a folder of its own: the user's stays untouched,
    and tests after the first compile of a model take the cache's load path."""
    import os
    import tempfile

    os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="pfaff-test-cache-")
