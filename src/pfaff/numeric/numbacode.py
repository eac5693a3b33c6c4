"""What pfaff's numba code is built on (imported only with that code, never with ``pfaff``).

``cached`` and ``helper`` (numba's compilation of a function, with or without its own entry in
numba's on-disk cache) and ``call_entry`` (a call through a C entry point
``void *f(double *out, const double *in, void *data)``, SymEngine's LLVM functions':
:func:`pfaff.numeric.machineloop.entry_point`); ``fresh`` (a cache entry dropped when the
module's sources changed). Used by the band LU (:mod:`pfaff.numeric.bandlu`), the compiled
passes of long arrays (:mod:`pfaff.numeric.jit`) and the compiled stepping loop
(:mod:`pfaff.integrate.loopkernel`).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import re
import tempfile
from pathlib import Path

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic


def helper(fn, **options):
    """A helper of a cached function: compiled with it (and kept in its cache entry);
    ``options`` are numba's (``inline="always"``, ``_nrt=False``)."""
    return njit(error_model="numpy", **options)(fn)


def cached(fn, **options):
    """``njit`` with numba's on-disk cache (beside the module, or numba's user-wide folder when
    that is read-only, or ``NUMBA_CACHE_DIR``), kept only while the sources of its module and
    of the pfaff modules it imports are those it was written from (:func:`fresh`); without it
    where no folder is writable."""
    try:
        return fresh(njit(cache=True, error_model="numpy", **options)(fn))
    except RuntimeError:  # "no locator available": compiled once per process instead
        return njit(error_model="numpy", **options)(fn)


@functools.cache
def source_digest(module: str) -> str:
    """SHA-256 of the sources ``module`` is made from: its file and, through every ``pfaff``
    import in them (at the top or inside a function, :func:`_imported`), the files
    of the pfaff modules it imports, transitively (a package's ``__init__`` counted, its
    re-exports not followed). Once per module and process.

    Examples
    --------
    >>> band, jit = source_digest("pfaff.numeric.bandlu"), source_digest("pfaff.numeric.jit")
    >>> len(band), band != jit  # (a hex SHA-256; other sources, another digest)
    (64, True)
    >>> sorted(p.name for p in _sources("pfaff.numeric.bandlu"))
    ['bandlu.py', 'numbacode.py']
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(_sources(module)):
        h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def _sources(module: str) -> set[Path]:
    """The files of ``module`` and of the pfaff modules it imports, transitively."""
    base = Path(__file__).resolve().parents[2]
    seen: set[Path] = set()
    todo = [module]
    while todo:
        name = todo.pop()
        path = base.joinpath(*name.split(".")).with_suffix(".py")
        package = not path.is_file()
        if package:
            path = base.joinpath(*name.split("."), "__init__.py")
        if not path.is_file() or path in seen:
            continue  # (a name imported from a module, not a module itself)
        seen.add(path)
        if not package or name == module:
            todo.extend(_imported(path, name if package else name.rpartition(".")[0]))
    return seen


_FROM = re.compile(r"^[ \t]*from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n#;]+)", re.M)
_IMPORT = re.compile(r"^[ \t]*import[ \t]+([^\n#;]+)", re.M)


def _imported(path: Path, package: str) -> list[str]:
    r"""The pfaff modules (and names from them) that the file ``path`` of ``package`` imports,
    anywhere in it: ``import a, b as c``, ``from a import (b, c)`` over several lines, relative
    imports, backslash continuations (read from the text: parsing the 23 files of the stepping
    loop would take 0.15 s of every process that loads it).

    Examples
    --------
    >>> import tempfile
    >>> text = "import os, pfaff.a as x\nfrom pfaff.b import (\n    c,\n    d as e,\n)\n"
    >>> text += "def f():\n    from .g import h\n"
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     _ = (Path(tmp) / "m.py").write_text(text)
    ...     sorted(_imported(Path(tmp) / "m.py", "pfaff.p"))
    ['pfaff.a', 'pfaff.b', 'pfaff.b.c', 'pfaff.b.d', 'pfaff.p.g', 'pfaff.p.g.h']
    """
    text = path.read_text(encoding="utf-8").replace("\\\n", " ")
    out = []
    for names in _IMPORT.findall(text):
        out += [n.split()[0] for n in names.split(",") if n.strip()]
    for dots, source, names in _FROM.findall(text):
        if dots:  # relative: from the package's own place
            parts = package.split(".")
            source = ".".join([*parts[: len(parts) - len(dots) + 1], source]).strip(".")
        words = [n.split()[0] for n in names.strip("()").split(",") if n.strip()]
        out += [source] + [f"{source}.{w}" for w in words]
    return [m for m in out if m == "pfaff" or m.startswith("pfaff.")]


def fresh(dispatcher):
    """``dispatcher`` (a cached numba function), its cache emptied first if the sources of its
    module (:func:`source_digest`) changed since the cache was written.

    numba keeps a cache entry while the function's own file keeps its time stamp and size and
    its bytecode is the same: a helper in another module, or a constant imported from one,
    could change and the old machine code would still be loaded. A file beside the cache
    records :func:`source_digest` of the function's module, the sources the entries were made
    from: a change elsewhere in pfaff keeps them (the stepping loop, about 11 s to compile,
    is compiled again only when one of its 23 files changes).

    Examples
    --------
    >>> def double(x):
    ...     return 2.0 * x
    >>> f = fresh(njit(double))  # (no cache: nothing to check)
    >>> f(2.0)
    4.0
    """
    cache = getattr(dispatcher, "_cache", None)
    folder = getattr(cache, "_cache_path", None)
    if folder is None:  # no cache (or a numba whose cache this cannot read): nothing to check
        return dispatcher
    fn = dispatcher.py_func
    stamp = Path(folder) / f"{fn.__module__}.{fn.__qualname__}.pfaff-sources"
    digest = source_digest(fn.__module__)
    with contextlib.suppress(OSError):
        if stamp.read_text() == digest:
            return dispatcher
    cache.flush()  # machine code of other sources: compiled anew
    with contextlib.suppress(OSError):  # (a folder numba cannot write either: no cache)
        os.makedirs(folder, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".pfaff-sources.")
        try:
            with os.fdopen(fd, "w") as fh:
                fh.write(digest)
            os.replace(tmp, stamp)
        finally:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
    return dispatcher


@intrinsic
def call_entry(typingctx, addr, out, inp, data):
    """Call ``void *f(double *out, const double *in, void *data)`` at the address ``addr``."""
    sig = types.void(types.int64, out, inp, types.int64)

    def codegen(context, builder, signature, args):
        a, o, i, d = args
        dptr, vptr = ir.DoubleType().as_pointer(), ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(vptr, [dptr, dptr, vptr])
        fptr = builder.inttoptr(a, fnty.as_pointer())
        oarr = context.make_array(signature.args[1])(context, builder, o)
        iarr = context.make_array(signature.args[2])(context, builder, i)
        builder.call(fptr, [oarr.data, iarr.data, builder.inttoptr(d, vptr)])
        return context.get_dummy_value()

    return sig, codegen
