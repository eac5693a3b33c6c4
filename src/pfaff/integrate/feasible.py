"""Method/size combinations refused before running: IDA's dense Newton matrix.

IDA here factors a dense Newton matrix of ``size = 2n + m + m_h`` unknowns (SUNDIALS' dense LU,
``size³/3`` operations each time the matrix is rebuilt). A family of a few thousand members
would take hours: it is refused up front, with the estimate, instead of hanging.

How the constant was measured (``SECONDS_PER_CUBE``): scikit-sundae's IDA with a dense ``jacfn``
on the linear DAE ``y' + K y = 0`` (K = I + 0.01·noise) of 400, 800 and 1200 unknowns over
t ∈ [0, 1], on the project's 2-core machine while busy: total time / Jacobian evaluations /
size³ = 4.7e-10, 9.1e-10, 5.5e-10 s (median 5.5e-10), with 15 to 18 evaluations per run
(``FACTORIZATIONS``, the fewest a run makes). Raise ``LIMIT_SECONDS`` or drop the check when IDA
on families becomes sparse.
"""

from __future__ import annotations

from pfaff.core.errors import OptionError
from pfaff.core.memory import refuse_beyond

SECONDS_PER_CUBE = 5.5e-10  # seconds per (unknown)³ of one dense factorization (measured above)
FACTORIZATIONS = 15  # the fewest Newton matrices a run builds (measured above)
LIMIT_SECONDS = 3600.0  # an estimate beyond this is refused


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
    >>> refuse_dense_ida(500, 200)
    >>> refuse_dense_ida(8_000, 2_500)  # 1.4 GiB, 1.2 h: the time (the memory on a small machine)
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
