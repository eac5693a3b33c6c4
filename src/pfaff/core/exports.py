"""A package's public names, imported on first use (PEP 562 module ``__getattr__``).

``import pfaff`` runs no more than its table of names: the command line starts, and installs its
interrupt path (:mod:`pfaff.cli.signals`), before SymPy, NumPy or any stage loads, so that Ctrl-C
while the stages import ends it with one line as it does later; a script loads the stages it
uses, on the first access of one of their names.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping


def lazy_exports(
    package: str, table: Mapping[str, str]
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package`` for the names of ``table``.

    Parameters
    ----------
    package : str
        The package's name (its ``__name__``).
    table : mapping of str to str
        Public name -> the module it is imported from; a name whose module is
        ``package + "." + name`` is that module itself.

    Returns
    -------
    getattr, dir : callable
        To assign to the package's ``__getattr__`` and ``__dir__``: a name is imported once and
        then set on the package (no second lookup).

    Examples
    --------
    >>> getattr_, dir_ = lazy_exports("pfaff", {"coordinates": "pfaff.core.symbols"})
    >>> getattr_("coordinates").__name__, "coordinates" in dir_()
    ('coordinates', True)
    >>> getattr_("nothing")
    Traceback (most recent call last):
    AttributeError: module 'pfaff' has no attribute 'nothing'
    """

    def __getattr__(name: str) -> object:
        where = table.get(name)
        if where is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module = importlib.import_module(where)
        value = module if where == f"{package}.{name}" else getattr(module, name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(table))

    return __getattr__, __dir__
