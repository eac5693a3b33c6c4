"""The closed rolling ring: the seed's ring with all n spacing rows, one of them redundant.

``rolling_ring(n, closed=True)`` adds ``spacing n``, θ_1 − θ_n − 2π/n + 2π = 0, to the n − 1 rows
θ_{k+1} − θ_k − 2π/n = 0. The n spacing rows sum to the no-op 0 = 0, so Aᵀ has the null space
spanned by w = (0, 1, …, 1) (zero on ``no slip``): a hoop stress that moves nothing. The checks of
the model itself evaluate the constraint expressions directly with SymPy and NumPy, never through
pfaff's derivation or solver. The motion (θ̈ = F/(2Mr), λ_1 = −F/2) through pfaff, which accepts
the redundant row (the family form: its solver drops the closing row, known from the structure).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff

NS = (2, 3, 6)
FORMS = {"explicit": False, "family": True}
M, R, F = 2.0, 0.5, 3.0


def constraint_exprs(system: pfaff.System) -> list[sp.Expr]:
    """Every constraint row f(q) as a global expression, family templates expanded per k."""
    rows = []
    for piece in system.constraints:
        (expr,) = piece.exprs
        tmpl = piece.template
        if tmpl is None:
            rows.append(expr)
            continue
        refs = {
            f: ref
            for fam in system.families
            for f, ref in fam.refs.items()
            if ref.index == tmpl.index
        }
        for k in range(tmpl.lo, tmpl.hi + 1):
            rows.append(
                expr.xreplace({f: ref.family.member(ref.member(k)) for f, ref in refs.items()})
            )
    return rows


def coordinates(system: pfaff.System) -> list[sp.Expr]:
    return list(system.coordinates)


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("n", NS)
def test_builds_with_n_plus_one_rows(n: int, form: str) -> None:
    ring = pfaff.models.rolling_ring(n, force=True, closed=True, family=FORMS[form])
    names, holonomic = ring.constraint_rows()
    assert ring.n == n + 1
    assert ring.n_constraints == n + 1
    assert list(names) == ["no slip", *(f"spacing {k}" for k in range(1, n + 1))]
    assert holonomic.all()


@pytest.mark.parametrize("form", FORMS)
def test_open_ring_unchanged(form: str) -> None:
    """``closed=False`` (the default) is today's ring: n rows, no ``spacing n``."""
    ring = pfaff.models.rolling_ring(4, family=FORMS[form])
    names, _ = ring.constraint_rows()
    assert ring.n_constraints == 4
    assert list(names) == ["no slip", "spacing 1", "spacing 2", "spacing 3"]


@pytest.mark.parametrize("n", NS)
def test_forms_write_the_same_rows(n: int) -> None:
    explicit = constraint_exprs(pfaff.models.rolling_ring(n, closed=True, family=False))
    family = constraint_exprs(pfaff.models.rolling_ring(n, closed=True, family=True))
    assert len(explicit) == n + 1
    assert [sp.simplify(a - b) for a, b in zip(explicit, family, strict=True)] == [0] * (n + 1)


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("n", NS)
def test_closing_row_sign(n: int, form: str) -> None:
    """``spacing n`` is the n-th row of the pattern θ_{k+1} − θ_k − 2π/n with θ_{n+1} = θ_1 + 2π."""
    ring = pfaff.models.rolling_ring(n, closed=True, family=FORMS[form])
    th = coordinates(ring)[1:]
    closing = constraint_exprs(ring)[-1]
    assert sp.simplify(closing - ((th[0] + 2 * sp.pi) - th[-1] - 2 * sp.pi / n)) == 0


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("n", NS)
def test_residuals_vanish_on_ring_state(n: int, form: str) -> None:
    ring = pfaff.models.rolling_ring(n, radius=R, closed=True, family=FORMS[form])
    f = sp.lambdify(coordinates(ring), constraint_exprs(ring), "numpy")
    for theta in (0.0, 0.3, -2.1, 7.5):
        q, _ = pfaff.models.ring_state(n, R, theta)
        np.testing.assert_allclose(f(*q), 0.0, atol=1e-12)
    q, _ = pfaff.models.ring_state(n, R, 0.3)
    q[-1] += 1e-3  # off the ring: the last spacing row and the closing row see it
    res = np.asarray(f(*q))
    assert abs(res[-1]) > 1e-4 and abs(res[-2]) > 1e-4


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("n", NS)
def test_spacing_rows_sum_to_the_no_op(n: int, form: str) -> None:
    """Σ spacing rows ≡ 0 symbolically: the loop is closed twice over."""
    rows = constraint_exprs(pfaff.models.rolling_ring(n, closed=True, family=FORMS[form]))
    assert sp.expand(sum(rows[1:])) == 0


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("n", NS)
def test_hoop_stress_spans_null_space_of_At(n: int, form: str) -> None:
    """A = ∂f/∂q: Aᵀ w = 0 for w = (0, 1, …, 1), and w spans the null space (rank A = n)."""
    ring = pfaff.models.rolling_ring(n, closed=True, family=FORMS[form])
    qs = coordinates(ring)
    A = sp.Matrix(constraint_exprs(ring)).jacobian(qs)
    w = sp.Matrix([0] + [1] * n)
    assert A.T * w == sp.zeros(n + 1, 1)
    q, _ = pfaff.models.ring_state(n, R, 0.7)
    An = np.array(A.subs({sp.Symbol("r"): R, **dict(zip(qs, q, strict=True))}), dtype=float)
    s = np.linalg.svd(An, compute_uv=False)
    assert np.linalg.matrix_rank(An) == n
    left = np.linalg.svd(An.T)[2][-1]  # right singular vector of Aᵀ for its zero singular value
    np.testing.assert_allclose(abs(left), np.r_[0.0, np.full(n, 1 / np.sqrt(n))], atol=1e-12)
    assert s[-1] < 1e-12


def _accelerations(n: int, family: bool, closed: bool) -> tuple[np.ndarray, np.ndarray]:
    ring = pfaff.models.rolling_ring(n, force=True, closed=closed, family=family)
    model = ring.equations().compile({"M": M, "r": R, "F": F})
    q, qd = pfaff.models.ring_state(n, R, 0.3, 1.2)
    qdd, lam = model.accelerations(0.0, q, qd)
    return np.asarray(qdd), np.asarray(lam)


@pytest.mark.parametrize("form", ["explicit", "family"])
@pytest.mark.parametrize("n", (3, 6))
def test_closed_ring_motion(n: int, form: str) -> None:
    """θ̈ = F/(2Mr), ẍ = F/(2M), λ_1 = −F/2; the spacing multipliers are the open ring's up to a
    hoop stress c·(1, …, 1)."""
    qdd, lam = _accelerations(n, FORMS[form], closed=True)
    np.testing.assert_allclose(qdd[1:], F / (2 * M * R), rtol=1e-12)
    np.testing.assert_allclose(qdd[0], F / (2 * M), rtol=1e-12)
    np.testing.assert_allclose(lam[0], -F / 2, rtol=1e-12)
    _, lam_open = _accelerations(n, FORMS[form], closed=False)
    hoop = lam[1:] - np.r_[lam_open[1:], 0.0]
    np.testing.assert_allclose(hoop - hoop.mean(), 0.0, atol=1e-10)
