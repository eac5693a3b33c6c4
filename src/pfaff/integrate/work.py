"""The work of the applied forces along a step: W_nc(t) = ∫ Qᵀq̇ dt for the energy balance.

Over a whole step, Runge–Kutta steppers integrate it with their own stages (``step_work``: the
method's order, no new right-hand side). Up to a reported time inside a step, Gauss–Legendre nodes
on the step's dense output (made anyway for that time). IDA uses the quintic Hermite interpolant
through q, q̇ and q̈ at both ends of its step, values it has already computed.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import numpy as np

from pfaff.core.errors import StateError
from pfaff.results.trajectory import hermite5_weights

GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(4)  # nodes on [-1, 1] and weights
# on the quintic Hermite interpolant three nodes suffice: exact for degree 5, like the interpolant
HERMITE_X, HERMITE_W = np.polynomial.legendre.leggauss(3)
# coordinates from which the dense output is asked for one node at a time: at the ring's 2^24
# particles the four nodes' states together are 1 GiB, beside K's 2.9 GiB
ONE_NODE_FROM = 1 << 16

FEW = 8  # a power reading at most 1/FEW of the coordinates gets states exact there only
Endpoint = tuple[float, np.ndarray, np.ndarray]  # (t, y = [q, q̇], ẏ = [q̇, q̈])


def read_coordinates(power: Callable, n: int) -> np.ndarray | None:
    """The coordinates a power names as the ones it reads (``coordinates``, as
    :class:`pfaff.numeric.quantities.StreamPower` does), where they are few (at most n / FEW:
    the ring's push reads x alone); None otherwise. The work integral's nodes then need their
    states there only (:func:`state_at`).

    Examples
    --------
    >>> class Push:
    ...     coordinates = np.array([0])
    >>> read_coordinates(Push(), 64).tolist(), read_coordinates(Push(), 4), read_coordinates(abs, 64)
    ([0], None, None)
    """
    idx = getattr(power, "coordinates", None)
    return None if idx is None or FEW * len(idx) > n else np.asarray(idx)


def state_at(y0: np.ndarray, idx: np.ndarray, q: np.ndarray, qd: np.ndarray) -> tuple:
    """(q, q̇): the state y0 = [q, q̇] with q[idx] and q̇[idx] replaced by ``q`` and ``qd`` (a
    node's state for a power that reads those coordinates alone; the rest is y0's, unread).

    Examples
    --------
    >>> state_at(np.arange(6.0), np.array([1]), np.array([9.0]), np.array([8.0]))
    (array([0., 9., 2.]), array([3., 8., 5.]))
    """
    n = len(y0) // 2
    qi, qdi = np.array(y0[:n]), np.array(y0[n:])
    qi[idx], qdi[idx] = q, qd
    return qi, qdi


def hermite_work(
    ends: tuple[Endpoint, Endpoint],
    power: Callable[[float, np.ndarray, np.ndarray], float],
    a: float,
    b: float,
) -> float:
    """∫ P dt over [a, b] inside the step between ``ends``, three Gauss–Legendre nodes; at
    the coordinates the power reads alone where it names few of them (:func:`read_coordinates`).

    Examples
    --------
    >>> y0, y1 = np.array([0.0, 1.0]), np.array([1.0, 1.0])   # q = t, q̇ = 1 on [0, 1]
    >>> f = np.array([1.0, 0.0])
    >>> round(hermite_work(((0.0, y0, f), (1.0, y1, f)), lambda t, q, v: float(q[0]), 0.0, 1.0), 12)
    0.5
    """
    if b <= a:
        return 0.0
    (t0, y0, f0), (t1, y1, f1) = ends
    n, h = len(y0) // 2, t1 - t0
    ts = a + (b - a) * (HERMITE_X + 1.0) / 2.0
    # the six Hermite weights at each node (floats), applied to the end values by one product;
    # where the power names the few coordinates it reads (the ring's push: x alone), only there
    # (the rest of each node's state is the step's start: the power does not read it)
    W = [hermite5_weights((float(ti) - t0) / h, h) for ti in ts]
    idx = read_coordinates(power, n)
    cols = slice(None) if idx is None else idx
    parts = (y0[:n], y0[n:], f0[n:], y1[:n], y1[n:], f1[n:])
    Y = np.empty((6, n if idx is None else len(idx)))  # (rows: contiguous, not a column stack)
    for row, part in zip(Y, parts, strict=True):
        row[:] = part[cols]
    q, qd = np.array([w[0] for w in W]) @ Y, np.array([w[1] for w in W]) @ Y
    p = []
    for i, ti in enumerate(ts):
        qi, qdi = (q[i], qd[i]) if idx is None else state_at(y0, idx, q[i], qd[i])
        p.append(power(float(ti), qi, qdi))
    return 0.5 * (b - a) * checked_sum([w * v for w, v in zip(HERMITE_W, p, strict=True)], b)


def dense_work(
    dense: Callable[[np.ndarray], list[tuple[np.ndarray, np.ndarray]]],
    power: Callable[[float, np.ndarray, np.ndarray], float],
    a: float,
    b: float,
) -> float:
    """∫ P dt over [a, b] with four Gauss–Legendre nodes on a stepper's dense output ``dense``
    (for a reported time inside a Runge–Kutta step, whose interpolant is then made anyway)."""
    if b <= a:
        return 0.0
    ts = a + (b - a) * (GAUSS_X + 1.0) / 2.0
    states = dense(ts[:1])
    if states[0][0].shape[0] >= ONE_NODE_FROM:  # long states: one node's state alive at a time
        states = itertools.chain(states, (dense(ts[i : i + 1])[0] for i in range(1, len(ts))))
    else:
        states += dense(ts[1:])
    p = [power(float(ti), q, qd) for ti, (q, qd) in zip(ts, states, strict=True)]
    return 0.5 * (b - a) * checked_sum([w * v for w, v in zip(GAUSS_W, p, strict=True)], b)


def checked_sum(terms: list[float], t: float) -> float:
    """``math.fsum`` of finite terms; an overflowing power is a failure at ``t``, not a crash."""
    if not all(math.isfinite(v) and abs(v) < 1e300 for v in terms):
        raise StateError(f"the power of the applied forces overflows near t = {t:.17g}")
    return math.fsum(terms)
