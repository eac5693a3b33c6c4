"""Model files of the sweep tests."""

from __future__ import annotations

from pathlib import Path

import pytest

PENDULUM = """
[model]
name = "pendulum"
coordinates = ["theta"]
parameters = { m = 1.0, L = 1.0, g = 9.81 }
potential = "-m*g*L*cos(theta)"

[[particles]]
name = "bob"
mass = "m"
position = ["L*sin(theta)", "-L*cos(theta)"]

[initial]
q = { theta = 0.01 }

[simulate]
t_end = 4.0
"""

CARTESIAN = """
[model]
name = "Cartesian pendulum"
coordinates = ["x", "y"]
parameters = { m = 2.0, L = 1.0, g = 9.81 }
potential = "m*g*y"

[[particles]]
mass = "m"
position = ["x", "y"]

[[constraints]]
name = "rod"
holonomic = "x**2 + y**2 - L**2"

[initial]
q = { x = 0.0, y = -1.0 }

[simulate]
t_end = 2.0
method = "projection"
rtol = 1e-10
atol = 1e-12
"""


@pytest.fixture
def pendulum(tmp_path: Path) -> Path:
    p = tmp_path / "pendulum.toml"
    p.write_text(PENDULUM)
    return p


@pytest.fixture
def cartesian(tmp_path: Path) -> Path:
    p = tmp_path / "cartesian.toml"
    p.write_text(CARTESIAN)
    return p
