"""sin and cos of one argument array in one compiled pass (numba), for the largest kernels.

:func:`pfaff.numeric.trig.sincos` shares an argument reduction between sin and cos in 27 NumPy
passes (13 ns a value for both on the 2-core development machine); a pass that does it all per
value in registers, vectorized by LLVM, takes 2.4 ns a value (measured on 2^15 values in cache,
AVX-512; 2.6 ns over 2^20 values from memory). Per value: k = rint(x 2/π), the reduced argument
r = x − k π/2 with π/2 in three parts (Cody and Waite: k P₁ and k P₂ exact for |k| < 2^20), Taylor
polynomials of sin r and cos r on |r| <= π/4 (truncation below 1e-19), and the quadrant k mod 4
choosing and signing them without a branch. Its multiplications and additions are fused into
multiply-adds where the CPU has them (:func:`pfaff.numeric.jit.compiled`'s ``contract``): 2.5–3.0
→ 1.6 ns a value on 2^15 values in cache (measured 2026-11-28). Absolute error about 1.4e-16
against mpmath for |x| <= :data:`pfaff.numeric.trig.LIMIT` (the C library's is 1.1e-16); a larger
|x|, a NaN or an infinity is handed to the C library's sin and cos afterwards (one flag per call).

The loop is compiled (or loaded from numba's on-disk cache) on first use, :func:`compiled`
(:mod:`pfaff.numeric.jit`); without numba, or where it fails, or with ``PFAFF_JIT=0``, the
callers keep :func:`pfaff.numeric.trig.sincos`. It releases the GIL, so the kernel threads
(:func:`pfaff.numeric.streams.in_spans`) run it side by side.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from pfaff.numeric import jit
from pfaff.numeric.trig import LIMIT

# π/2 = P1 + P2 + P3 to 1e-37: P1 and P2 of 33 significant bits (k P1, k P2 exact for |k| < 2^20)
P1 = float.fromhex("0x1.921fb54400000p+0")
P2 = float.fromhex("0x1.0b4611a600000p-34")
P3 = float.fromhex("0x1.3198a2e037073p-69")
TWO_OVER_PI = float.fromhex("0x1.45f306dc9c883p-1")
ROUND = 6755399441055744.0  # 1.5 · 2^52: (y + ROUND) - ROUND is y rounded to an integer

# sin r = r + r z (S3 + z (S5 + …)), cos r = 1 + z (C2 + z (C4 + …)), z = r²: Taylor coefficients
_S = tuple((-1) ** (k // 2) / math.factorial(k) for k in range(3, 18, 2))  # S3 … S17
_C = tuple((-1) ** (k // 2) / math.factorial(k) for k in range(2, 19, 2))  # C2 … C18


def _source(x, s, c):  # type: ignore[no-untyped-def]
    """The loop numba compiles: x (contiguous) → s = sin x, c = cos x."""
    s3, s5, s7, s9, s11, s13, s15, s17 = _S
    c2, c4, c6, c8, c10, c12, c14, c16, c18 = _C
    outside = 0
    for i in range(x.shape[0]):
        xi = x[i]
        k = (xi * TWO_OVER_PI + ROUND) - ROUND
        r = ((xi - k * P1) - k * P2) - k * P3
        z = r * r
        p = s15 + z * s17
        p = s3 + z * (s5 + z * (s7 + z * (s9 + z * (s11 + z * (s13 + z * p)))))
        sr = r + r * z * p
        u = c16 + z * c18
        u = c2 + z * (c4 + z * (c6 + z * (c8 + z * (c10 + z * (c12 + z * (c14 + z * u))))))
        cr = 1.0 + z * u
        quadrant = np.int64(k) & 3
        a = sr if (quadrant & 1) == 0 else cr
        b = cr if (quadrant & 1) == 0 else sr
        s[i] = a if (quadrant & 2) == 0 else -a
        c[i] = b if ((quadrant + 1) & 2) == 0 else -b
        outside |= not (abs(xi) <= LIMIT)  # (NaN too)
    if outside:
        for i in range(x.shape[0]):
            if not (abs(x[i]) <= LIMIT):
                s[i] = math.sin(x[i])
                c[i] = math.cos(x[i])


def compiled() -> Callable | None:
    """The compiled ``f(x, sin_out, cos_out)`` (contiguous float64 arrays), or None
    (:func:`pfaff.numeric.jit.compiled`); asked for on the calling thread, before any kernel
    thread runs it."""
    x = np.zeros(1)
    return jit.compiled(_source, (x, np.empty(1), np.empty(1)), contract=True)


def sincos(fn: Callable, x: np.ndarray, s: np.ndarray, c: np.ndarray, tmp: np.ndarray) -> None:
    """sin x into ``s`` and cos x into ``c`` with the compiled ``fn`` (from :func:`compiled`);
    a strided x is first copied into ``tmp`` (a contiguous loop vectorizes, a strided one not).

    Parameters
    ----------
    fn : callable
        :func:`compiled`'s function.
    x : ndarray, shape (k,)
    s, c : ndarray, shape (k,), contiguous
    tmp : ndarray, shape (>= k,)
        Scratch for a strided x.

    Examples
    --------
    >>> fn = compiled()
    >>> x = np.linspace(-20.0, 20.0, 1001)
    >>> s, c = np.empty(1001), np.empty(1001)
    >>> if fn is not None:
    ...     sincos(fn, x, s, c, np.empty(1001))
    ... else:
    ...     s, c = np.sin(x), np.cos(x)
    >>> bool(np.abs(s - np.sin(x)).max() < 3e-16 and np.abs(c - np.cos(x)).max() < 3e-16)
    True
    """
    if not x.flags.c_contiguous:
        if tmp.shape[0] < x.shape[0]:
            tmp = np.empty(x.shape[0])
        np.copyto(tmp[: x.shape[0]], x)
        x = tmp[: x.shape[0]]
    fn(x, s, c)
