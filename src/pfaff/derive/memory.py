"""Memory estimates: refuse a model that cannot fit before allocating anything of size N."""

from __future__ import annotations

import os

from pfaff.core.errors import ModelError

BYTES_PER_ROW = 8 * 14  # float64 work arrays per coordinate or constraint row in one solve
ROWS_FOR_CHECK = 1 << 16  # below this, never bother


def available_bytes() -> int:
    """Memory available to this process: MemAvailable from /proc/meminfo, else physical memory."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 1 << 62


def estimate_bytes(eom) -> int:
    """Rough peak bytes of compiling and solving ``eom`` numerically.

    Every template output may be an array over its instances; the solve holds about 14 float64
    vectors of length n + m (state, right-hand sides, band, projections, results).

    Examples
    --------
    >>> import pfaff
    >>> eom = pfaff.models.rolling_ring(2**20, family=True).equations()
    >>> 0.1 < estimate_bytes(eom) / 2**30 < 1
    True
    """
    total = BYTES_PER_ROW * (eom.n + eom.m)
    for b in eom.blocks:
        loc = b.local
        outs = len(loc.mass) + len(loc.h) + len(loc.Q) + len(loc.A) + 3
        total += 8 * b.n_inst * outs // 2  # about half the outputs vary with the state
    return total


def check_memory(eom, fraction: float = 0.85) -> None:
    """Raise ModelError when the estimate exceeds ``fraction`` of the available memory."""
    if eom.n + eom.m < ROWS_FOR_CHECK:
        return
    need, have = estimate_bytes(eom), available_bytes()
    if need > fraction * have:
        raise ModelError(
            f"this model ({eom.n} coordinates, {eom.m} constraints) needs about "
            f"{need / 2**30:.1f} GiB to solve numerically, but only {have / 2**30:.1f} GiB of "
            "memory is available: use fewer members"
        )
