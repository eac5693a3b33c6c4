"""What a family run keeps of size N: the forcing vector in a run buffer, a band's head and tail."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff
from pfaff.numeric.banded import LowerBand
from pfaff.numeric.streams import Index


def test_inplace_rhs_buffer_cleared_between_states() -> None:
    """A ring on an incline under gravity and a push: forcing on x and on every θ_k. Three
    in-place evaluations at different states give the q̈ of fresh solves (a buffer that kept
    an earlier state's forcing would not), and the closed form of the uniform ring at rest."""
    n, M, r, F, g, a = 8, 2.0, 0.5, 3.0, 9.81, 0.3
    sys_ = pfaff.models.rolling_ring(n, family=True, force=F, gravity=g, incline=a)
    model = sys_.equations().compile({"M": M, "r": r}).for_run()
    forcing = [ix for part in model.dyn for ix in part.forcing]
    assert any(isinstance(ix, Index) and not ix.fixed for ix in forcing)
    field = model.ode_function()
    rng = np.random.default_rng(3)
    q0, qd0 = pfaff.models.ring_state(n, r, theta=1.0)
    out = np.empty(2 * model.n)
    for k in range(3):
        q, qd = q0 + 0.01 * k, qd0 + rng.normal(size=model.n)
        field.into(0.0, np.concatenate([q, qd]), out)
        fresh, _ = model.solve(0.0, q, qd)
        np.testing.assert_allclose(out[model.n :], fresh, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(out[: model.n], qd)
    field.into(0.0, np.concatenate([q0, 0.0 * qd0]), out)  # uniform ring at rest
    xdd = (F / M + g * np.sin(a)) / 2  # ẍ = (F + M g sin α)/(2M) for a hoop rolling down
    np.testing.assert_allclose(out[model.n], xdd, rtol=1e-12)


@pytest.mark.slow  # (its first use of scipy.signal: 1.2 s of import)
def test_constant_band_keeps_head_and_tail_only() -> None:
    """A bandwidth-2 band with a head of 3 irregular rows and a constant tail (the lfilter
    path): the solves agree with dense triangular solves, and of its m columns the band keeps
    the head, the w after it and the tail's coefficients."""
    m = 400
    R = np.vstack([np.full(m, 2.0), np.full(m, -0.5), np.full(m, 0.25)])
    R[:, :3] = [[1.5, -2.0, 3.0], [0.0, 0.7, -1.1], [0.0, 0.0, 0.4]]
    L = np.diag(R[0]) + np.diag(R[1, 1:], -1) + np.diag(R[2, 2:], -2)
    band = LowerBand(R, constant=True)
    assert band.method == "lfilter" and band.R.shape[1] == band.head + band.w + 2 < m
    c = np.random.default_rng(2).normal(size=m)
    np.testing.assert_allclose(band.solve(c), np.linalg.solve(L, c), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(band.solve_t(c), np.linalg.solve(L.T, c), rtol=1e-10, atol=1e-12)
