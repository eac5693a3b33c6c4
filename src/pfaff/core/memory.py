"""The memory this process may still use (for the estimates that refuse or warn up front)."""

from __future__ import annotations

import os

from pfaff.core.errors import OptionError


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


def refuse_beyond(need: float, what: str, advice: str) -> None:
    """Refuse (an :class:`OptionError`) what would need more than half the available memory.

    Examples
    --------
    >>> refuse_beyond(2.0**70, "--samples 10**20", "report fewer times")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pfaff.core.errors.OptionError: --samples 10**20 would need about 1.1e+12 GiB, more than half ...
    """
    have = available_bytes()
    if need > have / 2:
        raise OptionError(
            f"{what} would need about {need / 2**30:.3g} GiB, more than half the memory "
            f"available ({have / 2**30:.3g} GiB): {advice}"
        )
