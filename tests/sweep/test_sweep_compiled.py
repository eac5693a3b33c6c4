"""pfaff.sweep of a compiled model: initial state and time span given, vary keys as for files."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff


@pytest.fixture(scope="module")
def spring() -> pfaff.NumericModel:
    """m ẍ + k x = 0."""
    x = pfaff.coordinates("x")
    m, k = sp.symbols("m k")
    s = pfaff.System([x])
    s.add_particle(m, [x, 0])
    s.add_potential_energy(k * x**2 / 2)
    return s.equations().compile({"m": 2.0, "k": 8.0})


def test_grid_of_a_compiled_model_against_closed_form(spring) -> None:
    """x = x0 cos ω(t − t0) + v0/ω sin ω(t − t0), ω = √(k/m), over k × q0.x × qd0.x."""
    ks, x0s, v0s = [2.0, 8.0], [0.5, 1.0], [0.0, -1.0]
    ds = pfaff.sweep(
        spring,
        {"k": ks, "q0.x": x0s, "qd0.x": v0s},
        q0=[3.0],
        t_span=(1.0, 4.0),
        samples=31,
        options={"rtol": 1e-11},
        scheduler="synchronous",
    )
    assert ds.q.dims == ("k", "q0.x", "qd0.x", "time", "coordinate")
    assert (ds.status == "success").all() and ds.attrs["model"] == "compiled model"
    t = ds.time.values
    np.testing.assert_array_equal(t, np.linspace(1.0, 4.0, 31))
    for k in ks:
        w = np.sqrt(k / 2.0)
        for x0 in x0s:
            for v0 in v0s:
                exact = x0 * np.cos(w * (t - 1.0)) + v0 / w * np.sin(w * (t - 1.0))
                got = ds.q.sel({"k": k, "q0.x": x0, "qd0.x": v0, "coordinate": "x"}).values
                np.testing.assert_allclose(got, exact, rtol=0, atol=1e-9)
    assert spring.parameters == {"k": 8.0, "m": 2.0}  # the user's model is unchanged


def test_the_base_state_and_values_of_the_model(spring) -> None:
    """Unvaried: q0 and qd0 as given (qd0 defaults to rest), the model's own parameters."""
    ds = pfaff.sweep(spring, {"m": [2.0]}, q0=[1.0], t_span=(0.0, np.pi), samples=3,
                     scheduler="synchronous")  # fmt: skip
    np.testing.assert_allclose(ds.q.sel(m=2.0, coordinate="x").values, [1, -1, 1], atol=1e-6)
    ds = pfaff.sweep(spring, {"m": [8.0]}, q0=[0.0], qd0=[1.0], t_span=(0.0, np.pi / 2),
                     samples=2, scheduler="synchronous")  # fmt: skip
    # ω = 1: x = sin t
    assert float(ds.q.sel(m=8.0, coordinate="x").values[-1]) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"t_span": (0, 1)}, pfaff.OptionError, r"needs `q0`"),
        ({"q0": [1.0]}, pfaff.OptionError, r"needs `t_span`"),
        ({"q0": [1.0, 2.0], "t_span": (0, 1)}, pfaff.StateError, r"`q0`"),
        ({"q0": [1.0], "qd0": "fast", "t_span": (0, 1)}, pfaff.StateError, r"`qd0`"),
        ({"q0": [1.0], "t_span": (1, 1)}, pfaff.OptionError, r"t_end must be after t0"),
        ({"q0": [1.0], "t_span": (0, np.nan)}, pfaff.OptionError, r"`t_span\[1\]`"),
        ({"q0": [1.0], "t_span": 3.0}, pfaff.OptionError, r"a pair \(t0, t_end\)"),
        ({"q0": [1.0], "t_span": (0, 1), "t_end": 2}, pfaff.OptionError, r"not both"),
        ({"q0": [1.0], "t_span": (0, 1), "options": 3}, pfaff.OptionError, r"`options`"),
    ],
)
def test_bad_arguments_named(spring, kwargs, error, match) -> None:
    with pytest.raises(error, match=match):
        pfaff.sweep(spring, {"k": [1.0]}, scheduler="synchronous", **kwargs)


def test_bad_vary_names_the_model_names(spring) -> None:
    with pytest.raises(pfaff.OptionError, match=r"`q0.y` is not q0.<coordinate>.*: x\)"):
        pfaff.sweep(spring, {"q0.y": [1.0]}, q0=[1.0], t_span=(0, 1), scheduler="synchronous")
    with pytest.raises(pfaff.OptionError, match=r"`c` is neither a parameter \(k, m\)"):
        pfaff.sweep(spring, {"c": [1.0]}, q0=[1.0], t_span=(0, 1), scheduler="synchronous")


def test_a_file_takes_t_span_and_options(tmp_path) -> None:
    path = tmp_path / "spring.toml"
    path.write_text(
        '[model]\ncoordinates = ["x"]\nparameters = { m = 1.0, k = 1.0 }\n'
        'kinetic = "m*dot(x)**2/2"\npotential = "k*x**2/2"\n[initial]\nq = { x = 1.0 }\n'
    )
    ds = pfaff.sweep(path, {"k": [4.0]}, t_span=(0.5, 0.5 + np.pi), samples=2,
                     options={"method": "baumgarte"}, scheduler="synchronous")  # fmt: skip
    assert ds.attrs["method"] == "baumgarte" and ds.time.values.tolist() == [0.5, 0.5 + np.pi]
    assert float(ds.q.values[0, -1, 0]) == pytest.approx(1.0, abs=1e-6)  # cos(2π)
