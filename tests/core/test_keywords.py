"""A misspelled keyword of a public function or method: a KeywordError (a pfaff error and a
TypeError) naming it, the closest valid keyword, and every keyword of the signature."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from pathlib import Path

import pytest

import pfaff

EXAMPLE = Path(__file__).parents[2] / "examples" / "pendulum.toml"


@pytest.fixture(scope="module")
def pendulum() -> pfaff.NumericModel:
    return pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})


def _calls(model: pfaff.NumericModel) -> list[tuple[Callable, tuple, str, str]]:
    s = pfaff.models.cartesian_pendulum()
    x, y = s.coordinates
    return [
        (pfaff.simulate, (model, [1, 0], [0, 0], (0, 1)), "rtl", "rtol"),
        (pfaff.consistent_state, (model, [1, 0], [0, 0], ["x"]), "max_iters", "max_iter"),
        (pfaff.load_model, (EXAMPLE,), "max_byte", "max_bytes"),
        (s.add_particle, (1, [x, y]), "nme", "name"),
        (s.add_potential_energy, (x,), "nam", "name"),
        (s.equations().compile, ({"m": 1, "g": 9.81, "L": 1},), "evaluatr", "evaluator"),
    ]


@pytest.mark.parametrize("k", range(6))
def test_misspelled_keyword_is_named(pendulum: pfaff.NumericModel, k: int) -> None:
    fn, args, bad, good = _calls(pendulum)[k]
    with pytest.raises(pfaff.KeywordError, match=f"unexpected keyword argument `{bad}`") as info:
        fn(*args, **{bad: 1})
    assert isinstance(info.value, TypeError) and isinstance(info.value, pfaff.PfaffError)
    message = str(info.value)
    if good is not None:
        assert f"did you mean `{good}`?" in message
    listed = message.split("(its keywords: ")[1].rstrip(")").split(", ")
    sig = inspect.signature(fn).parameters.values()
    named = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    assert listed == [p.name for p in sig if p.kind in named]


def test_valid_keywords_still_work(pendulum: pfaff.NumericModel) -> None:
    tr = pfaff.simulate(pendulum, [1, 0], [0, 0], t_span=(0, 0.5), rtol=1e-8, t_eval=[0.5])
    assert tr.status == "success"


def test_every_public_function_names_a_misspelled_keyword() -> None:
    """The keyword is checked before anything else, so no valid argument is needed."""
    named = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    for name in pfaff.__all__:
        fn = getattr(pfaff, name)
        if not inspect.isfunction(fn) or name == "coordinates":  # (coordinates: one string)
            continue
        params = inspect.signature(fn).parameters.values()
        if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
            continue  # (fit: its **options go to simulate, which names a misspelled one)
        with pytest.raises(pfaff.KeywordError, match=f"^{fn.__name__}\\(\\) got an unexpected"):
            fn(zz_not_a_keyword=1)
        assert any(p.kind in named for p in inspect.signature(fn).parameters.values())
