"""Model files with kinks, crafted work, odd encodings and numbers beyond a float: each refused
clearly where it enters, or read as written (a byte-order mark, sign() in a friction force)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pfaff
from pfaff.core.expansion import MAX_FUNCTION_TERMS, expanded_terms
from pfaff.core.safe_expr import parse_expression

BLOCK = """
[model]
name = "block"
coordinates = ["x"]
parameters = { mu = 0.3, g = 9.81, L = 1.0 }
{extra}

[[particles]]
mass = "1"
position = ["x", "0"]
"""


def write(tmp_path: Path, extra: str, name: str = "m.toml", prefix: bytes = b"") -> Path:
    p = tmp_path / name
    p.write_bytes(prefix + BLOCK.replace("{extra}", extra).encode())
    return p


@pytest.mark.parametrize("term", ["abs(x)", "sign(x)*x", "L*abs(x - L)"])
def test_kinks_in_a_potential_are_refused_not_crashing(tmp_path: Path, term: str) -> None:
    """abs() of a coordinate in a potential used to kill the process (SIGSEGV) and sign() to
    end in a printer error; the derivation differentiates it, so it is refused, named."""
    with pytest.raises(pfaff.ModelFileError, match=r"model\.potential: .*not differentiable"):
        pfaff.load_model(write(tmp_path, f'potential = "{term}"'))


def test_sign_in_a_friction_force_runs(tmp_path: Path) -> None:
    """Forces are not differentiated: Coulomb friction −μ g sign(ẋ) decelerates the block by
    μ g, so x(t) = v0 t − μ g t²/2 until it stops."""
    text = BLOCK.replace("{extra}", "") + (
        '\n[[generalized_forces]]\ncoordinate = "x"\nexpr = "-mu*g*sign(dot(x))"\n'
    )
    p = tmp_path / "friction.toml"
    p.write_text(text)
    mf = pfaff.load_model(p)
    params = {k: v for k, v in mf.parameters.items() if k != "L"}  # L: unused here
    model = mf.system.equations().compile(params)
    v0, ts = 1.0, np.array([0.0, 0.1, 0.2, 0.3])
    tr = pfaff.simulate(model, [0.0], [v0], (0, 0.3), t_eval=ts)
    np.testing.assert_allclose(tr.q[:, 0], v0 * ts - 0.5 * 0.3 * 9.81 * ts**2, atol=1e-9)


@pytest.mark.parametrize("power", [8, 12, 40])
def test_crafted_expansions_are_refused_before_sympy_works(tmp_path: Path, power: int) -> None:
    """``abs(cosh((x + L + g)**8))`` took SymPy 4 s to build, ``**12`` 22 s: the argument's
    expanded size is counted from the sizes alone, and refused."""
    force = f'[[generalized_forces]]\ncoordinate = "x"\nexpr = "abs(cosh((x + L + g)**{power}))"'
    with pytest.raises(pfaff.ModelError, match=r"would expand to \d+ terms \(at most 16\)"):
        pfaff.load_model(write(tmp_path, force))


def test_expanded_terms_counts_the_multinomial() -> None:
    """C(n + k − 1, k − 1) terms for (a sum of k terms)**n, checked against SymPy's expand."""
    import sympy as sp

    x, y, z = sp.symbols("x y z")
    for e in ((x + y + z) ** 4, (x + y) ** 3 * (x - z), (x + 2 * y) ** 2 + sp.cos(x + y) * z):
        assert expanded_terms(e) >= len(sp.Add.make_args(sp.expand(e)))
    assert expanded_terms((x + y + z) ** 4) == len(sp.Add.make_args(sp.expand((x + y + z) ** 4)))
    assert expanded_terms((x + y + z) ** 5) > MAX_FUNCTION_TERMS
    # functions whose evaluation does not expand keep long arguments
    names = {"x": x, "y": y, "z": z}
    assert parse_expression("sqrt((x + y + z)**5)", names) == sp.sqrt((x + y + z) ** 5)


def test_byte_order_mark_is_read(tmp_path: Path) -> None:
    plain = pfaff.load_model(write(tmp_path, 'potential = "g*x"'))
    marked = pfaff.load_model(write(tmp_path, 'potential = "g*x"', "b.toml", b"\xef\xbb\xbf"))
    assert marked.system.equations().forcing == plain.system.equations().forcing


def test_huge_integers_and_overflowing_constants_are_refused(tmp_path: Path) -> None:
    big = "7" * 5000
    with pytest.raises(pfaff.ModelFileError, match="more digits than Python reads"):
        p = tmp_path / "n.toml"
        p.write_text(BLOCK.replace("mu = 0.3", f"mu = {big}").replace("{extra}", ""))
        pfaff.load_model(p)
    with pytest.raises(pfaff.ModelError, match="an integer has more than 100 digits"):
        pfaff.load_model(write(tmp_path, f'potential = "g*x*{big}"'))
    for const in ("10**400", "1e308*1e308"):
        with pytest.raises(pfaff.ModelError, match="beyond the floating-point range"):
            pfaff.load_model(write(tmp_path, f'potential = "g*x*{const}"'))
