"""Memory estimates: refuse a model that cannot fit before allocating anything of size N."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from pfaff.core.errors import ModelError
from pfaff.core.memory import available_bytes
from pfaff.derive.blocks import raw_keys

if TYPE_CHECKING:
    from pfaff.derive.blocks import Block

BYTES_PER_ROW = 8 * 14  # float64 work arrays per coordinate or constraint row in one solve
ROWS_FOR_CHECK = 1 << 16  # below this, never bother


def estimate_bytes(n: int, m: int, blocks: Sequence[Block]) -> int:
    """Rough peak bytes of compiling and solving a model numerically.

    Works from the sizes alone (nothing of size n is allocated), so it can run before the
    :class:`~pfaff.derive.equations.Derivation` is built. Every template output may be an array
    over its instances; the solve holds about 14 float64 vectors of length n + m (state,
    right-hand sides, band, projections, results).

    Parameters
    ----------
    n, m : int
        Number of coordinates and of constraint rows.
    blocks : sequence of Block
        The derived templates (:func:`pfaff.derive.templates.group`).

    Returns
    -------
    int

    Examples
    --------
    >>> import pfaff
    >>> from pfaff.derive.templates import group
    >>> ring = pfaff.models.rolling_ring(2**20, family=True)
    >>> 0.1 < estimate_bytes(ring.n, ring.n_constraints, group(ring)) / 2**30 < 1
    True
    """
    total = BYTES_PER_ROW * (n + m)
    for b in blocks:
        loc = b.local
        outs = len(raw_keys(loc.mass)) + len(raw_keys(loc.h)) + len(loc.Q) + len(loc.A) + 3
        total += 8 * b.n_inst * outs // 2  # about half the outputs vary with the state
    return total


def check_memory(n: int, m: int, blocks: Sequence[Block], *, fraction: float = 0.85) -> None:
    """Raise ModelError when :func:`estimate_bytes` exceeds ``fraction`` of the available memory.

    Parameters
    ----------
    n : int
        Number of coordinates.
    m : int
        Number of constraint rows.
    blocks : sequence of Block
        The derived templates.
    fraction : float, optional
        Share of the available memory a model may use (default 0.85).

    Raises
    ------
    ModelError
        When the model cannot fit.
    """
    n, m = int(n), int(m)
    if n + m < ROWS_FOR_CHECK:
        return
    need, have = estimate_bytes(n, m, blocks), available_bytes()
    if need > fraction * have:
        raise ModelError(
            f"this model ({n} coordinates, {m} constraints) needs about "
            f"{need / 2**30:.1f} GiB to solve numerically, but only {have / 2**30:.1f} GiB of "
            "memory is available: use fewer members"
        )
