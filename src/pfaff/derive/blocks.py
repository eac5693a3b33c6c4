"""The derivation stage's data: a template's local Lagrange terms and the instances that share it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp


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
