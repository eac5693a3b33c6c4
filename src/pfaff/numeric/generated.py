"""Generated functions that travel: their source text and the names it uses, made again by ``exec``.

Compiled models hold functions generated at compile time (template kernels by
:func:`sympy.lambdify`, the fused kernel by :mod:`pfaff.derive.fused`). A function object does
not pickle; its source does. :class:`Portable` is what a pickle carries instead of such a
function: the source (registered in :mod:`linecache` when it was generated), the function's
name, and the objects its code refers to by name (NumPy ufuncs and ``math`` functions pickle by
reference; modules by their name). Loading runs the same source, so the function computes
bit for bit what the original did. The source is pfaff's own generated code, never user text.
"""

from __future__ import annotations

import hashlib
import importlib
import linecache
import types
from collections.abc import Callable
from dataclasses import dataclass


def register(source: str, tag: str) -> str:
    """A unique file name for generated ``source``, with the source in :mod:`linecache` (for
    tracebacks and for :meth:`Portable.of`).

    Examples
    --------
    >>> name = register("def f(x):\\n    return x + 1\\n", "example")
    >>> name.startswith("<pfaff.generated example ")
    True
    """
    digest = hashlib.sha1(source.encode(), usedforsecurity=False).hexdigest()[:16]
    filename = f"<pfaff.generated {tag} {digest}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    return filename


def _names(code: types.CodeType) -> set[str]:
    out = set(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            out |= _names(c)
    return out


@dataclass(frozen=True)
class Portable:
    """A generated function as data: ``source``, the function's ``name`` and its ``namespace``
    (name -> object, or ``("module", name)`` for a module).

    Examples
    --------
    >>> import math, pickle
    >>> src = "def f(x):\\n    return sin(x) + 1\\n"
    >>> ns = {"sin": math.sin}
    >>> exec(compile(src, register(src, "doc"), "exec"), ns)
    >>> g = pickle.loads(pickle.dumps(Portable.of(ns["f"]))).load()
    >>> g(0.5) == ns["f"](0.5)
    True
    """

    source: str
    name: str
    namespace: tuple

    @classmethod
    def of(cls, fn: Callable) -> Portable:
        """The portable form of a function generated from registered source."""
        code = fn.__code__  # type: ignore[attr-defined]
        generated = code.co_filename.startswith(("<pfaff.generated ", "<lambdifygenerated"))
        source = "".join(linecache.getlines(code.co_filename)) if generated else ""
        if not source:
            raise TypeError(f"the source of generated function {fn.__name__} is not known")
        glb = fn.__globals__  # type: ignore[attr-defined]
        items = []
        for name in sorted(_names(code)):
            if name not in glb or name == "__builtins__":
                continue
            value = glb[name]
            if isinstance(value, types.ModuleType):
                value = ("module", value.__name__)
            items.append((name, value))
        return cls(source, fn.__name__, tuple(items))

    def load(self) -> Callable:
        """The function, made again from its source."""
        ns: dict = {}
        for name, value in self.namespace:
            if isinstance(value, tuple) and len(value) == 2 and value[0] == "module":
                value = importlib.import_module(value[1])
            ns[name] = value
        exec(compile(self.source, register(self.source, "loaded"), "exec"), ns)  # pfaff's own code
        return ns[self.name]


def portable(fn: Callable | None) -> Portable | Callable | None:
    """:meth:`Portable.of` of a generated function; None and callable objects (which pickle
    themselves) pass through."""
    if fn is None or not isinstance(fn, types.FunctionType):
        return fn
    return Portable.of(fn)


def loaded(p: Portable | Callable | None) -> Callable | None:
    """:meth:`Portable.load`, passing functions and None through."""
    return p.load() if isinstance(p, Portable) else p
