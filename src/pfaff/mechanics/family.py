"""Indexed families: N coordinates θ_k, and pieces given by one template over a range of k.

A :class:`Family` is a block of coordinates ``theta[first] … theta[first + n - 1]`` appended to a
:class:`pfaff.System`. Indexing it with an integer gives one member (an ordinary coordinate named
``theta5``); indexing it with an affine expression of an index symbol (``theta[k + 1]``, ``x[2*k]``)
gives a *reference*, usable in a template that ``System.add_*(..., over=k)`` instantiates for every k
of a range. The template is localized and derived once; its instances exist only as index
arithmetic (slices), so neither the symbolic nor the numeric model creates per-instance objects.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ModelError, ModelTypeError
from pfaff.core.lazy import LazySeq
from pfaff.core.symbols import t

MAX_FAMILY = 2**31 - 1  # index arithmetic is int64, but keep the numbers sane


@dataclass(frozen=True)
class Ref:
    """A template reference ``family[stride*k + shift]``."""

    family: Family
    stride: int
    shift: int
    index: sp.Symbol

    def member(self, k: int) -> int:
        """Family member index (``first``-based) at k."""
        return self.stride * k + self.shift

    def column(self, k: int) -> int:
        """Global coordinate index at k."""
        return self.family.offset + self.member(k) - self.family.first


class Family:
    """Coordinates ``name{first}`` … ``name{first + n - 1}`` of a :class:`pfaff.System`.

    Made by :meth:`pfaff.System.add_family`. ``fam[i]`` (an integer) is member i, an ordinary
    coordinate; ``fam[k + 1]`` (k an index symbol) is a template reference for ``over=k`` pieces.

    Attributes
    ----------
    name : str
    n : int
        Number of members.
    first : int
        Index of the first member.
    offset : int
        Global coordinate index of the first member.

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> x = pfaff.coordinates("x")
    >>> s = pfaff.System([x])
    >>> theta = s.add_family("theta", 4, first=1)
    >>> k = sp.Symbol("k", integer=True)
    >>> theta[2], theta[k + 1], s.n
    (theta2(t), theta[k + 1](t), 5)
    """

    def __init__(self, name: str, n: int, first: int, offset: int) -> None:
        self.name, self.n, self.first, self.offset = name, n, first, offset
        self.refs: dict[AppliedUndef, Ref] = {}

    @property
    def last(self) -> int:
        """Index of the last member."""
        return self.first + self.n - 1

    def member(self, i: int) -> sp.Expr:
        """Member i as a coordinate (a function of t)."""
        return sp.Function(f"{self.name}{i}")(t)

    @property
    def coordinates(self) -> Sequence:
        """All members, made on demand."""
        return LazySeq(self.n, lambda j: self.member(self.first + j))

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, index: object) -> sp.Expr:
        if isinstance(index, int | np.integer) and not isinstance(index, bool):
            i = int(index)
            if not self.first <= i <= self.last:
                raise ModelError(
                    f"`{self.name}[{i}]` is out of range: the family has members "
                    f"{self.name}{self.first} … {self.name}{self.last}"
                )
            return self.member(i)
        if not isinstance(index, sp.Expr):
            raise ModelTypeError(
                f"`{self.name}[...]` takes an integer or an affine expression of an index symbol "
                f"such as k + 1, got {type(index).__name__} {index!r}"
            )
        k, stride, shift = affine(index, f"`{self.name}[{index}]`")
        ref = sp.Function(f"{self.name}[{index}]")(t)
        self.refs[ref] = Ref(self, stride, shift, k)
        return ref

    def __repr__(self) -> str:
        return f"<pfaff.Family {self.name}{self.first} … {self.name}{self.last}>"


def affine(index: sp.Expr, what: str) -> tuple[sp.Symbol, int, int]:
    """Split ``a*k + c`` (a, c integers, a != 0) into (k, a, c)."""
    free = index.free_symbols
    if len(free) != 1:
        raise ModelError(f"{what}: the index must involve exactly one index symbol, got {index}")
    (k,) = free
    poly = sp.Poly(index, k) if index.is_polynomial(k) else None
    if poly is None or poly.degree() != 1:
        raise ModelError(f"{what}: the index must be affine in {k} (like 2*{k} + 1), got {index}")
    a, c = poly.coeff_monomial(k), poly.coeff_monomial(1)
    if not (a.is_Integer and c.is_Integer):
        raise ModelError(f"{what}: index coefficients must be integers, got {index}")
    return k, int(a), int(c)


def member_index(families: Sequence[Family], f: AppliedUndef) -> int | None:
    """Global index of a concrete family member such as ``theta5(t)``, or None."""
    name = f.func.__name__
    for fam in families:
        rest = name[len(fam.name) :]
        if name.startswith(fam.name) and rest.isdigit() and str(int(rest)) == rest:
            i = int(rest)
            if fam.first <= i <= fam.last:
                return fam.offset + i - fam.first
    return None


def find_ref(families: Sequence[Family], f: AppliedUndef) -> Ref | None:
    """The template reference ``f`` stands for, or None."""
    for fam in families:
        ref = fam.refs.get(f)
        if ref is not None:
            return ref
    return None


def check_name(name: object, n: object, first: object, taken: Sequence[str]) -> tuple[str, int]:
    """Validate the arguments of ``System.add_family``."""
    if not isinstance(name, str) or not name.isidentifier():
        raise ModelTypeError(f"family `name` must be an identifier such as 'theta', got {name!r}")
    for nn, what in ((n, "n"), (first, "first")):
        if not isinstance(nn, int | np.integer) or isinstance(nn, bool):
            raise ModelTypeError(f"family `{what}` must be an integer, got {nn!r}")
    if not 1 <= int(n) <= MAX_FAMILY:
        raise ModelError(f"family `{name}` needs 1 <= n <= {MAX_FAMILY} members, got {n}")
    clash = [s for s in taken if s.startswith(name) or name.startswith(s)]
    clash = [s for s in clash if s == name or s[len(name) :].isdigit() or name[len(s) :].isdigit()]
    if clash:
        raise ModelError(
            f"family `{name}` clashes with the coordinate or family name(s) "
            f"{', '.join(sorted(clash))}: member names {name}0, {name}1, … must be unambiguous"
        )
    return name, int(n)


def index_range(refs: Sequence[Ref], over: object, what: str) -> tuple[sp.Symbol, int, int]:
    """The index symbol and inclusive range (lo, hi) of a template, checked against its families.

    ``over`` is the index symbol (range: the whole family it indexes as ``fam[k]``) or a tuple
    ``(k, lo, hi)`` with ``hi`` inclusive, as in :class:`sympy.Sum`.
    """
    if isinstance(over, tuple):
        if len(over) != 3 or not isinstance(over[0], sp.Symbol):
            raise ModelTypeError(f"{what}: `over` must be k or (k, first, last), got {over!r}")
        k = over[0]
        try:
            lo, hi = int(over[1]), int(over[2])
        except (TypeError, ValueError):
            raise ModelTypeError(f"{what}: range bounds must be integers, got {over!r}") from None
    elif isinstance(over, sp.Symbol):
        k, lo, hi = over, None, None
    else:
        raise ModelTypeError(f"{what}: `over` must be an index symbol k or (k, first, last)")
    mine = [r for r in refs if r.index == k]
    others = sorted({str(r.index) for r in refs if r.index != k})
    if others:
        raise ModelError(f"{what}: references indexed by {', '.join(others)}, but over={k}")
    if not mine:
        raise ModelError(f"{what}: over={k} but the template references no family by {k}")
    if lo is None:
        plain = [r for r in mine if r.stride == 1 and r.shift == 0] or mine[:1]
        lengths = {(r.family.name, r.family.n) for r in plain}
        if len({n for _, n in lengths}) > 1:
            desc = ", ".join(f"{name} has {n}" for name, n in sorted(lengths))
            raise ModelError(f"{what}: mismatched family lengths over {k} ({desc} members)")
        lo, hi = _solve_range(plain[0])
    if lo > hi:
        raise ModelError(f"{what}: empty range {k} = {lo} … {hi}")
    for r in mine:
        for kk in (lo, hi):
            i = r.member(kk)
            if not r.family.first <= i <= r.family.last:
                raise ModelError(
                    f"{what}: {r.family.name}[{r.stride}*{k} + {r.shift}] at {k} = {kk} is "
                    f"{r.family.name}{i}, out of range ({r.family.name}{r.family.first} … "
                    f"{r.family.name}{r.family.last}); give the range explicitly, "
                    f"e.g. over=({k}, first, last)"
                )
    return k, lo, hi


def _solve_range(r: Ref) -> tuple[int, int]:
    """k range over which ``r`` sweeps exactly its family's members (r = stride*k + shift)."""
    f = r.family
    a, b = sorted(((f.first - r.shift) / r.stride, (f.last - r.shift) / r.stride))
    return int(np.ceil(a)), int(np.floor(b))
