"""Method/size combinations refused before running: IDA's Newton matrices, dense and sparse.

IDA here factors a dense Newton matrix of ``size = 2n + m + m_h`` unknowns (SUNDIALS' dense LU,
``size³/3`` operations each time the matrix is rebuilt). A family of a few thousand members
would take hours: it is refused up front, with the estimate, instead of hanging.

How the constant was measured (``SECONDS_PER_CUBE``): scikit-sundae's IDA with a dense ``jacfn``
on the linear DAE ``y' + K y = 0`` (K = I + 0.01·noise) of 400, 800 and 1200 unknowns over
t ∈ [0, 1], on the project's 2-core machine while busy: total time / Jacobian evaluations /
size³ = 4.7e-10, 9.1e-10, 5.5e-10 s (median 5.5e-10), with 15 to 18 evaluations per run
(``FACTORIZATIONS``, the fewest a run makes).

A family's IDA assembles a sparse Newton matrix instead (:mod:`pfaff.numeric.ggl`), O(size) in
time and memory. Measured on the pushed ring (4N + 2 unknowns; N = 2^12, 2^14, 2^16; the
2-core machine at a load of 16): one assembly and SuperLU factorization 1.28e-6, 1.45e-6,
1.15e-6 s per unknown (CPU; ``SPARSE_SECONDS_PER_UNKNOWN`` = 1.3e-6), and the peak resident
memory of the pattern, one factorization and its work arrays 1143, 837, 889 bytes per unknown
(``SPARSE_BYTES_PER_UNKNOWN`` = 1400 with IDA's own vectors and a margin). The memory refuses
first: the ring of 2^22 particles needs about 22 GiB, of 2^20 about 5.5 GiB.
"""

from __future__ import annotations

from pfaff.core.errors import OptionError
from pfaff.core.memory import refuse_beyond

SECONDS_PER_CUBE = 5.5e-10  # seconds per (unknown)³ of one dense factorization (measured above)
FACTORIZATIONS = 15  # the fewest Newton matrices a run builds (measured above)
LIMIT_SECONDS = 3600.0  # an estimate beyond this is refused
SPARSE_SECONDS_PER_UNKNOWN = 1.3e-6  # one sparse Newton matrix, assembled and factored (below)
SPARSE_BYTES_PER_UNKNOWN = 1400.0  # peak memory of a family's IDA run per unknown (below)


def ida_estimate(size: int) -> float:
    """Seconds at least that IDA's dense Newton matrices of ``size`` unknowns take in one run.

    Examples
    --------
    >>> round(ida_estimate(1000), 2)  # 15 factorizations of 1000³ · 5.5e-10 s
    8.25
    """
    return FACTORIZATIONS * SECONDS_PER_CUBE * float(size) ** 3


def refuse_dense_ida(size: int, n: int) -> None:
    """Refuse (OptionError) IDA on ``size`` unknowns (``n`` coordinates) when its dense Newton
    matrices would take longer than ``LIMIT_SECONDS`` or more than half the memory.

    Examples
    --------
    The second is refused by time, or first by memory where little is free:

    >>> refuse_dense_ida(500, 200)
    >>> refuse_dense_ida(8_000, 2_500)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pfaff.core.errors.OptionError: method 'ida' on 2500 coordinates ...
    """
    refuse_beyond(
        3 * 8.0 * size * size,  # the Newton matrix, its LU and our copy, float64
        f"method 'ida' on {n} coordinates (a dense Newton matrix of {size} unknowns)",
        "use method='projection' (sparse for families)",
    )
    seconds = ida_estimate(size)
    if seconds > LIMIT_SECONDS:
        raise OptionError(
            f"method 'ida' on {n} coordinates factors a dense Newton matrix of {size} unknowns: "
            f"at least {FACTORIZATIONS} factorizations of about {seconds / FACTORIZATIONS:.3g} s "
            f"each, {seconds / 3600:.2g} h or more (measured {SECONDS_PER_CUBE:.2g} s per "
            f"unknown³), beyond the limit of {LIMIT_SECONDS / 3600:g} h: use "
            "method='projection' (sparse for families)"
        )


def sparse_ida_estimate(size: int) -> tuple[float, float]:
    """(seconds, bytes) at least that IDA on a family of ``size`` unknowns takes: the sparse
    Newton matrix assembled and factored ``FACTORIZATIONS`` times, and its pattern, factors and
    work arrays (:mod:`pfaff.numeric.ggl`).

    Examples
    --------
    >>> seconds, nbytes = sparse_ida_estimate(4 * 2**16 + 2)  # the ring of 2^16 particles
    >>> round(seconds, 1), round(nbytes / 2**30, 2)
    (5.1, 0.34)
    """
    return (
        FACTORIZATIONS * SPARSE_SECONDS_PER_UNKNOWN * float(size),
        SPARSE_BYTES_PER_UNKNOWN * float(size),
    )


def refuse_sparse_ida(size: int, n: int) -> None:
    """Refuse (OptionError) IDA on a family of ``size`` unknowns (``n`` coordinates) when its
    sparse Newton matrices would take longer than ``LIMIT_SECONDS`` or more than half the
    memory (:func:`sparse_ida_estimate`).

    Examples
    --------
    >>> refuse_sparse_ida(4 * 2**16 + 2, 2**16 + 1)
    >>> refuse_sparse_ida(4 * 2**30 + 2, 2**30 + 1)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pfaff.core.errors.OptionError: method 'ida' on 1073741825 coordinates ...
    """
    seconds, nbytes = sparse_ida_estimate(size)
    what = f"method 'ida' on {n} coordinates (a sparse Newton matrix of {size} unknowns)"
    refuse_beyond(nbytes, what, "use method='projection'")
    if seconds > LIMIT_SECONDS:
        raise OptionError(
            f"{what}: at least {FACTORIZATIONS} factorizations of about "
            f"{seconds / FACTORIZATIONS:.3g} s each, {seconds / 3600:.2g} h or more (measured "
            f"{SPARSE_SECONDS_PER_UNKNOWN:.2g} s per unknown), beyond the limit of "
            f"{LIMIT_SECONDS / 3600:g} h: use method='projection'"
        )
