"""A scheduler address with a port outside 1–65535 is refused by name, before any socket."""

from __future__ import annotations

from pathlib import Path

import pytest

import pfaff

EXAMPLE = Path(__file__).parents[2] / "examples" / "pendulum.toml"


@pytest.mark.parametrize("port", [0, 65536, 99999999])
def test_out_of_range_port(port: int) -> None:
    with pytest.raises(pfaff.OptionError, match=f"the port {port} of .* is not 1-65535"):
        pfaff.sweep(EXAMPLE, {"g": [9.0, 10.0]}, samples=3, scheduler=f"tcp://127.0.0.1:{port}")
