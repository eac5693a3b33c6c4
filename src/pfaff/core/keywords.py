"""Keyword arguments checked by name: a misspelled one is a :class:`pfaff.errors.KeywordError`
naming it, the closest valid keyword and all of them, not Python's bare ``TypeError``."""

from __future__ import annotations

import difflib
import functools
import inspect
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from pfaff.core.errors import KeywordError

P = ParamSpec("P")
R = TypeVar("R")

_NAMED = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)


def checked_keywords(fn: Callable[P, R]) -> Callable[P, R]:
    """``fn`` with its keyword arguments checked against its signature first.

    Examples
    --------
    >>> @checked_keywords
    ... def run(t_end, *, rtol=1e-9, atol=1e-11):
    ...     return t_end
    >>> run(1.0, rtl=1e-6)
    Traceback (most recent call last):
    ...
    pfaff.core.errors.KeywordError: run() got an unexpected keyword argument `rtl`; did you mean `rtol`? (its keywords: t_end, rtol, atol)
    """
    params = inspect.signature(fn).parameters.values()
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return fn
    names = [p.name for p in params if p.kind in _NAMED and p.name != "self"]
    known = frozenset(names)
    title = fn.__name__

    @functools.wraps(fn)
    def checked(*args: P.args, **kwargs: P.kwargs) -> R:
        if kwargs and not known.issuperset(kwargs):
            bad = next(k for k in kwargs if k not in known)
            close = difflib.get_close_matches(bad, names, n=1)
            hint = f"; did you mean `{close[0]}`?" if close else ""
            raise KeywordError(
                f"{title}() got an unexpected keyword argument `{bad}`{hint} "
                f"(its keywords: {', '.join(names) or 'none'})"
            )
        return fn(*args, **kwargs)

    return checked
