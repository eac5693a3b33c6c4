"""The derivation stage's data: a template's local Lagrange terms and the instances that share it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp


def _lazy_entries(raw: dict, convert: object, done: bool, converted: dict) -> LazyEntries:
    """A :class:`LazyEntries` from its pickled parts."""
    out = LazyEntries(raw, convert)
    dict.update(out, converted)
    out._done = done
    return out


class LazyEntries(dict):
    """A template's entries as SymPy, converted from their SymEngine forms on first use.

    ``raw`` holds the entries as SymEngine made them; ``convert(raw_entry)`` gives the SymPy
    entry (tidied) or 0 (then dropped). Nothing on the way from a small system to numbers reads
    them (its fused kernel is generated from ``raw``): on the Whipple bicycle the conversion was
    two thirds of ``equations()``. Any read (``[]``, ``len``, iteration, ``dict(...)``) converts
    them all once; ``raw_keys()`` is the pattern without converting (it may hold entries that
    only the SymPy clean-up finds to be zero).
    """

    def __init__(self, raw: dict, convert: object) -> None:
        super().__init__()
        self.raw, self._convert = raw, convert
        self._done = False

    def __reduce__(self) -> tuple:
        converted = dict(dict.items(self)) if self._done else {}
        return (_lazy_entries, (self.raw, self._convert, self._done, converted))

    def _materialize(self) -> None:
        if not self._done:
            self._done = True
            for key, e in self.raw.items():
                v = self._convert(e)
                if v != 0:
                    dict.__setitem__(self, key, v)

    def raw_keys(self) -> list:
        """The keys of the raw entries (a superset of the converted keys)."""
        return list(self.raw) if not self._done else list(dict.keys(self))

    def __getitem__(self, key: object) -> object:
        self._materialize()
        return dict.__getitem__(self, key)

    def __setitem__(self, key: object, value: object) -> None:
        self._materialize()
        dict.__setitem__(self, key, value)

    def __iter__(self):  # type: ignore[override]
        self._materialize()
        return dict.__iter__(self)

    def __len__(self) -> int:
        self._materialize()
        return dict.__len__(self)

    def __contains__(self, key: object) -> bool:
        self._materialize()
        return dict.__contains__(self, key)

    def __eq__(self, other: object) -> bool:
        self._materialize()
        return dict.__eq__(self, other)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        self._materialize()
        return dict.__repr__(self)

    def keys(self):  # type: ignore[override]
        self._materialize()
        return dict.keys(self)

    def values(self):  # type: ignore[override]
        self._materialize()
        return dict.values(self)

    def items(self):  # type: ignore[override]
        self._materialize()
        return dict.items(self)

    def get(self, key: object, default: object = None) -> object:
        self._materialize()
        return dict.get(self, key, default)

    def copy(self) -> dict:
        self._materialize()
        return dict(dict.items(self))

    def pop(self, *args: object) -> object:
        self._materialize()
        return dict.pop(self, *args)


def raw_keys(entries: dict) -> list:
    """The keys of a template's entries, without converting lazy ones."""
    return entries.raw_keys() if isinstance(entries, LazyEntries) else list(entries)


@dataclass
class Local:
    """Symbolic contributions of one template, in local coordinates ``_q0, _q1, ...``.

    ``mass`` holds both (a, b) and (b, a) entries; ``forcing`` is Q - h. Constraint templates fill
    ``A``, ``b``, ``bias`` (= Ȧq̇ + ḃ) and, when holonomic, ``f``. ``engine``, for a template
    differentiated in SymEngine, keeps its entries as SymEngine made them (``"mass"``, ``"h"``,
    ``"kinetic"``, ``"potential"``), so code generation need not convert them back.
    """

    kind: str
    k: int
    mass: dict[tuple[int, int], sp.Expr] = field(default_factory=dict)
    h: dict[int, sp.Expr] = field(default_factory=dict)
    Q: dict[int, sp.Expr] = field(default_factory=dict)
    kinetic: sp.Expr = sp.S.Zero
    potential: sp.Expr = sp.S.Zero
    A: dict[int, sp.Expr] = field(default_factory=dict)
    b: sp.Expr = sp.S.Zero
    bias: sp.Expr = sp.S.Zero
    f: sp.Expr | None = None
    engine: dict | None = None  # the same entries as SymEngine derived them (see templates)

    @property
    def forcing(self) -> dict[int, sp.Expr]:
        """Q - h by local coordinate."""
        out = dict(self.Q)
        for a, e in self.h.items():
            out[a] = out.get(a, sp.S.Zero) - e
        return {a: e for a, e in out.items() if e != 0}


class Block:
    """A template and the instances that share it.

    Attributes
    ----------
    local : Local
        The derived template.
    coords : ndarray of int, shape (n_inst, k)
        Global coordinate index of each local coordinate, per instance (made on first use for a
        family block).
    rows : ndarray of int, shape (n_inst,) or None
        Global constraint (multiplier) index per instance, for constraint blocks.
    pieces : list of Piece
        The model pieces of the instances.
    progressions : list of (start, step) or None
        For a family block: local coordinate a of instance i is ``start + step * i``.
    row0 : int
        For a family constraint block: the row of instance 0 (rows are consecutive).
    """

    def __init__(
        self,
        local: Local,
        coords: np.ndarray | None,
        rows: np.ndarray | None,
        pieces: list,
        *,
        progressions: list[tuple[int, int]] | None = None,
        n_inst: int = 0,
        row0: int = -1,
    ) -> None:
        self.local, self.pieces = local, pieces
        self._coords, self._rows = coords, rows
        self.progressions, self.row0 = progressions, row0
        self.n_inst = coords.shape[0] if coords is not None else n_inst

    @property
    def coords(self) -> np.ndarray:
        """Global coordinate indices, shape (n_inst, k)."""
        if self._coords is None:
            i = np.arange(self.n_inst, dtype=np.int64)
            cols = [start + step * i for start, step in self.progressions or []]
            self._coords = np.stack(cols, axis=1) if cols else np.zeros((self.n_inst, 0), np.int64)
        return self._coords

    @property
    def rows(self) -> np.ndarray | None:
        """Global constraint rows, shape (n_inst,), or None for a dynamics block."""
        if self._rows is None and self.row0 >= 0:
            self._rows = np.arange(self.row0, self.row0 + self.n_inst, dtype=np.int64)
        return self._rows

    @property
    def family(self) -> bool:
        """True for a block made from one family template."""
        return self.progressions is not None
