"""numba's on-disk cache is kept only while the sources a function is made from are those it was
written from (:func:`pfaff.numeric.numbacode.fresh`): numba itself checks only the function's own
file."""

from __future__ import annotations

import ast
import importlib.util
import sys
from pathlib import Path

import pytest

numbacode = pytest.importorskip("pfaff.numeric.numbacode")  # (numba)
from numba import njit  # noqa: E402


def _function(folder: Path):
    """A function in a module file of its own (numba caches beside it)."""
    path = folder / "cached_twice.py"
    path.write_text("def twice(x):\n    return 2.0 * x\n")
    spec = importlib.util.spec_from_file_location("cached_twice", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["cached_twice"] = module
    spec.loader.exec_module(module)
    return module.twice


def _hits(fn) -> tuple[int, int]:
    """(cache hits, cache misses) of one call of a fresh dispatcher of ``fn``."""
    d = numbacode.fresh(njit(cache=True)(fn))
    assert d(1.5) == 3.0
    return sum(d.stats.cache_hits.values()), sum(d.stats.cache_misses.values())


def test_the_cache_is_emptied_when_the_sources_change(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    fn = _function(tmp_path)
    try:
        assert _hits(fn) == (0, 1)  # compiled and saved
        stamps = list((tmp_path / "__pycache__").glob("*.pfaff-sources"))
        assert [p.read_text() for p in stamps] == [numbacode.source_digest("cached_twice")]
        assert _hits(fn) == (1, 0)  # the same sources: loaded
        monkeypatch.setattr(numbacode, "source_digest", lambda module: "other sources")
        assert _hits(fn) == (0, 1)  # other sources: compiled anew, not loaded
        assert stamps[0].read_text() == "other sources"
        assert _hits(fn) == (1, 0)
    finally:
        sys.modules.pop("cached_twice", None)


def _closure_by_syntax(module: str, src: Path) -> set[str]:
    """The same closure from Python's own parser (the independent method)."""
    seen: set[str] = set()
    todo = [module]
    while todo:
        name = todo.pop()
        rel = name.removeprefix("pfaff").lstrip(".").replace(".", "/")
        path, package = src / f"{rel}.py", False
        if not path.is_file():
            path, package = src / rel / "__init__.py", True
        key = path.relative_to(src).as_posix() if path.is_file() else None
        if key is None or key in seen:
            continue
        seen.add(key)
        if package and name != module:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                todo += [a.name for a in node.names if a.name.startswith("pfaff")]
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("pfaff"):
                todo += [node.module] + [f"{node.module}.{a.name}" for a in node.names]
    return seen


@pytest.mark.parametrize(
    "module", ["pfaff.integrate.loopkernel", "pfaff.numeric.bandlu", "pfaff.numeric.trigjit"]
)
def test_the_sources_of_a_module_are_the_pfaff_modules_it_imports(module: str) -> None:
    """A cached function's entry is made from its module and the pfaff modules it imports, at
    the top or inside a function, transitively: the same files as Python's parser finds, and
    not the stages above it."""
    src = Path(numbacode.__file__).resolve().parents[1]
    names = {p.relative_to(src).as_posix() for p in numbacode._sources(module)}
    assert names == _closure_by_syntax(module, src)
    assert not {n for n in names if n.split("/")[0] in {"api", "cli", "derive", "models"}}
    assert "numeric/numbacode.py" in names and "numeric/ggl.py" not in names
    assert numbacode.source_digest(module) != numbacode.source_digest("pfaff.numeric.jit")
