"""Lazy sequences: a length and an item function, for families too large to list (2^24 names)."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence

import numpy as np


class LazySeq(Sequence):
    """A read-only sequence whose items are made on demand by ``item(i)``.

    ``bulk(lo, hi)``, when given, makes the items lo … hi-1 at once (a list); iteration and
    slices use it, so that ``list(names)`` of a family of 2^20 members takes a fraction of a
    second rather than seconds of per-item calls.

    Examples
    --------
    >>> s = LazySeq(3, lambda i: i * i)
    >>> list(s), s[-1], len(s[1:])
    ([0, 1, 4], 4, 2)
    >>> b = LazySeq(5, lambda i: f"q{i}", bulk=lambda lo, hi: [f"q{i}" for i in range(lo, hi)])
    >>> list(b), b[1:3]
    (['q0', 'q1', 'q2', 'q3', 'q4'], ['q1', 'q2'])
    """

    BLOCK = 1 << 16

    def __init__(
        self,
        n: int,
        item: Callable[[int], object],
        bulk: Callable[[int, int], list] | None = None,
    ) -> None:
        self._n, self._item, self._bulk = int(n), item, bulk

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, i):  # type: ignore[override]
        if isinstance(i, slice):
            lo, hi, step = i.indices(self._n)
            if self._bulk is not None and step == 1:
                return self._bulk(lo, hi) if lo < hi else []
            return [self._item(j) for j in range(lo, hi, step)]
        j = int(i) + (self._n if i < 0 else 0)
        if not 0 <= j < self._n:
            raise IndexError(f"index {i} out of range for a sequence of {self._n}")
        return self._item(j)

    def __iter__(self) -> Iterator:
        if self._bulk is None:
            return (self._item(j) for j in range(self._n))
        return (
            x
            for lo in range(0, self._n, self.BLOCK)
            for x in self._bulk(lo, min(lo + self.BLOCK, self._n))
        )

    def __repr__(self) -> str:
        head = ", ".join(str(self._item(j)) for j in range(min(self._n, 3)))
        return f"<{self._n} items: {head}{', ...' if self._n > 3 else ''}>"


def concat(parts: Sequence[Sequence]) -> Sequence:
    """Concatenate sequences lazily (a tuple when every part is short).

    Examples
    --------
    >>> names = concat([["a", "b"], NumberedNames([], [("s", 1, 5000)])])
    >>> names[1:4], names[-1]
    (['b', 's1', 's2'], 's5000')
    """
    total = sum(len(p) for p in parts)
    if total <= 4096:
        return tuple(x for p in parts for x in p)
    return Concat(parts)


class Concat(LazySeq):
    """Sequences one after the other, items made on demand (it pickles as its parts)."""

    def __init__(self, parts: Sequence[Sequence]) -> None:
        self.parts = list(parts)
        self.starts = np.cumsum([0] + [len(p) for p in self.parts])
        super().__init__(int(self.starts[-1]), self._one, self._many)

    def __reduce__(self) -> tuple:
        return (Concat, (self.parts,))

    def _one(self, i: int) -> object:
        j = int(np.searchsorted(self.starts, i, side="right")) - 1
        return self.parts[j][i - int(self.starts[j])]

    def _many(self, lo: int, hi: int) -> list:
        """Items lo … hi-1, each part sliced once (its own bulk where it has one)."""
        out: list = []
        for part, s0, s1 in zip(
            self.parts, self.starts.tolist(), self.starts[1:].tolist(), strict=False
        ):
            a, b = max(lo, s0), min(hi, s1)
            if a < b:
                out += list(part[a - s0 : b - s0])
        return out


class NumberedNames(LazySeq):
    """Names made on demand: ``head`` as given, then numbered runs ``prefix + str(first + k)``.

    Unlike a :class:`LazySeq` of closures it pickles, in O(number of runs): a compiled model of
    2^24 particles carries its names without listing them.

    Parameters
    ----------
    head : sequence of str
        The first names, as they are.
    runs : sequence of (prefix, first, count)
        Then ``count`` names ``prefix{first}``, ``prefix{first + 1}``, … per run.

    Examples
    --------
    >>> names = NumberedNames(["x", "theta"], [("r", 1, 3), ("lambda", 5, 2)])
    >>> list(names), names[3], len(names)
    (['x', 'theta', 'r1', 'r2', 'r3', 'lambda5', 'lambda6'], 'r2', 7)
    >>> import pickle; pickle.loads(pickle.dumps(names))[-1]
    'lambda6'
    """

    def __init__(self, head: Sequence[str], runs: Sequence[tuple[str, int, int]]) -> None:
        self.head = [str(h) for h in head]
        self.runs = [(str(p), int(a), int(c)) for p, a, c in runs]
        self.starts = np.cumsum([len(self.head)] + [c for _, _, c in self.runs]).tolist()
        super().__init__(self.starts[-1], self._one, self._many)

    def __reduce__(self) -> tuple:
        return (NumberedNames, (self.head, self.runs))

    def _one(self, i: int) -> str:
        if i < len(self.head):
            return self.head[i]
        k = int(np.searchsorted(self.starts, i, side="right")) - 1
        prefix, first, _ = self.runs[k]
        return f"{prefix}{first + i - self.starts[k]}"

    def _many(self, lo: int, hi: int) -> list[str]:
        out = self.head[lo:hi]
        for (prefix, first, _), s0, s1 in zip(
            self.runs, self.starts, self.starts[1:], strict=False
        ):
            a, b = max(lo, s0), min(hi, s1)
            out += [f"{prefix}{first + j - s0}" for j in range(a, b)]
        return out
