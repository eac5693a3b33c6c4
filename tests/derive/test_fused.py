"""The fused scalar kernel (one generated function on floats) against the template kernels.

``compile()`` no longer evaluates the template kernels to check the fused one (they are generated
only when first needed); this suite checks the generator instead, on every small model of the zoo,
at random states: M, Q − h, b, Ȧq̇ + ḃ, f and g, the right-hand side, and the batched values.
"""

from __future__ import annotations

import numpy as np
import pytest

import pfaff

CASES = {
    "cartesian pendulum": (pfaff.models.cartesian_pendulum(), {"m": 1.3, "g": 9.81, "L": 0.7}),
    "pendulum": (pfaff.models.pendulum(), {"m": 1.3, "g": 9.81, "L": 0.7}),
    "ring of 3": (pfaff.models.rolling_ring(3, force=True), {"M": 1.1, "r": 0.4, "F": 0.3}),
    "3-link cart": (
        pfaff.models.n_link_pendulum_on_cart(3),
        {
            "m0": 1.0,
            "m1": 0.5,
            "m2": 0.7,
            "m3": 0.3,
            "l0": 0.8,
            "l1": 0.6,
            "l2": 0.5,
            "g": 9.81,
            "F": 0.4,
        },
    ),
}


@pytest.mark.parametrize("name", list(CASES))
def test_fused_kernel_matches_the_template_kernels(name: str) -> None:
    system, values = CASES[name]
    eom = system.equations()
    fused = eom.compile(values)
    plain = eom.compile(values, solver="lu")  # no fused kernel: the template kernels
    assert fused._fused is not None and fused._fused.rfn is not None and plain._fused is None
    rng = np.random.default_rng(4)
    ts = rng.uniform(0, 1, 4)
    Q = rng.uniform(-1, 1, (4, fused.n))
    QD = rng.uniform(-1, 1, (4, fused.n))
    for t, q, qd in zip(ts, Q, QD, strict=True):
        for a, b in zip(fused._kkt(t, q, qd), plain._kkt(t, q, qd), strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
        y = np.concatenate([q, qd])
        np.testing.assert_allclose(
            fused.ode_function()(t, y), plain.ode_function()(t, y), rtol=1e-9, atol=1e-9
        )
    a, b = fused.evaluate_states(ts, Q, QD), plain.evaluate_states(ts, Q, QD)
    for key in ("f", "g", "T", "V", "T0", "T2"):
        np.testing.assert_allclose(a[key], b[key], rtol=1e-11, atol=1e-12, err_msg=key)


@pytest.mark.parametrize("name", list(CASES))
def test_engine_and_sympy_assembly_agree(name: str, monkeypatch) -> None:
    """The fused kernel assembled in SymEngine from the templates, and from SymPy's assembly
    (the fallback for functions SymEngine does not share): the same outputs."""
    import pfaff.derive.fused as fused_mod

    monkeypatch.setenv("PFAFF_CACHE", "0")  # both generated here, neither loaded
    system, values = CASES[name]
    eom = system.equations()
    fast, status = fused_mod.build_fused(eom)
    assert status == "off"
    monkeypatch.setattr(fused_mod, "_engine_parts", lambda eom, args: None)
    slow, _ = fused_mod.build_fused(eom)
    p = [values[s.name] for s in eom.parameters]
    rng = np.random.default_rng(8)
    for _ in range(3):
        t, q, qd = rng.uniform(0, 1), rng.uniform(-1, 1, eom.n), rng.uniform(-1, 1, eom.n)
        args = (t, *q, *qd, *p)
        np.testing.assert_allclose(fast.fn(*args), slow.fn(*args), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(
            np.ravel(fast.efn(*args)), np.ravel(slow.efn(*args)), rtol=1e-12, atol=1e-12
        )


def test_new_parameter_values_reuse_the_generated_code() -> None:
    """The fused code takes the parameters at run time: a second compile with other values
    reuses it (no new code) and gives the accelerations of a fresh derivation with those values."""
    system, values = CASES["3-link cart"]
    eom = system.equations()
    first = eom.compile(values)
    other = dict(values, g=3.7, m2=2.5)
    second = eom.compile(other)
    assert second._fused.fn is first._fused.fn
    fresh = pfaff.models.n_link_pendulum_on_cart(3).equations().compile(other)
    rng = np.random.default_rng(2)
    q, qd = rng.uniform(-1, 1, 4), rng.uniform(-1, 1, 4)
    np.testing.assert_allclose(
        second.accelerations(0.0, q, qd)[0], fresh.accelerations(0.0, q, qd)[0], rtol=1e-12
    )
    assert not np.allclose(first.accelerations(0.0, q, qd)[0], fresh.accelerations(0.0, q, qd)[0])


@pytest.mark.parametrize("name", ["ring of 3", "3-link cart", "cartesian pendulum"])
@pytest.mark.parametrize("tau", [0.0, 1e-5, 1e3])  # no floor, the integrators' floor, all floored
def test_machine_code_rhs_matches_the_generated_python(name: str, tau: float) -> None:
    """The right-hand side compiled by SymEngine's LLVM backend against the generated Python
    (the same algorithm and floor), with Baumgarte terms, at random states off the manifold."""
    from pfaff.numeric.evaluator import machine_rhs as _machine_rhs

    system, values = CASES[name]
    model = system.equations().compile(values)
    fk = model._fused
    compiled = fk.llvm()
    if compiled is None:
        pytest.skip("this SymEngine has no LLVM backend")
    n, m = model.n, model.m
    fixed = [*model._p, 2.0, 3.0, *([tau] * m), tau]  # alpha, beta, taus, cap
    py = fk.rfn(*fixed, lambda t, y: pytest.fail("the slow path at a regular state"))
    fast = _machine_rhs(compiled, py, n, fixed)
    rng = np.random.default_rng(6)
    for _ in range(4):
        yl = rng.uniform(-1, 1, 2 * n).tolist()
        if name == "cartesian pendulum":
            yl[1] = -abs(yl[1]) - 0.5  # away from the pivot
        np.testing.assert_allclose(fast(0.3, yl), py(0.3, yl), rtol=1e-9, atol=1e-9)
