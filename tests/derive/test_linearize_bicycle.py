"""The Whipple bicycle linearized by pfaff against the published benchmark (Meijaard et al. 2007).

References, from J. P. Meijaard, J. M. Papadopoulos, A. Ruina, A. L. Schwab, Proc. R. Soc. A 463
(2007) 1955-1982:

* Table 2: the eigenvalues of the lean-steer equations at v = 0, 1, …, 10 m/s (14 digits);
* the weave and capsize speeds 4.29238253634111 and 6.02426201538837 m/s;
* the linearized equations M ẍ + v C1 ẋ + (g K0 + v² K2) x = 0 with the published matrices
  (:func:`pfaff.models.bicycle.meijaard_eigenvalues`).
"""

from __future__ import annotations

import numpy as np
import pytest

import pfaff
from pfaff.models.bicycle import (
    MEIJAARD_CAPSIZE_SPEED,
    MEIJAARD_WEAVE_SPEED,
    lean_steer_eigenvalues,
    meijaard_eigenvalues,
    stability_speeds,
)

# Equations of 8 coordinates and 5 constraints: about 3 s, then 0.15 s per speed.
pytestmark = pytest.mark.slow

# Meijaard et al. (2007), Table 2: per speed the eigenvalues of the benchmark bicycle's
# linearized lean and steer equations, sorted by real part, then imaginary part.
TABLE2 = {
    0: [-5.53094371765393, -3.13164324790656, 3.13164324790656, 5.53094371765393],
    1: [-7.11008014637442, -3.13423125066578, 3.52696170990070 - 0.80774027519930j,
        3.52696170990070 + 0.80774027519930j],
    2: [-8.67387984831735, -3.07158645641514, 2.68234517512745 - 1.68066296590675j,
        2.68234517512745 + 1.68066296590675j],
    3: [-10.35101467245920, -2.63366137253667, 1.70675605663975 - 2.31582447384325j,
        1.70675605663975 + 2.31582447384325j],
    4: [-12.15861426576447, -1.42944427361326, 0.41325331521125 - 3.07910818603206j,
        0.41325331521125 + 3.07910818603206j],
    5: [-14.07838969279822, -0.77534188219585 - 4.46486771378823j,
        -0.77534188219585 + 4.46486771378823j, -0.32286642900409],
    6: [-16.08537123098026, -1.52644486584142 - 5.87673060598709j,
        -1.52644486584142 + 5.87673060598709j, -0.00406690076970],
    7: [-18.15788466125262, -2.13875644258362 - 7.19525913329805j,
        -2.13875644258362 + 7.19525913329805j, 0.10268170574766],
    8: [-20.27940894394569, -2.69348683581097 - 8.46037971396931j,
        -2.69348683581097 + 8.46037971396931j, 0.14327879765713],
    9: [-22.43788559040858, -3.21675402252485 - 9.69377351531791j,
        -3.21675402252485 + 9.69377351531791j, 0.15790184030917],
    10: [-24.62459635017404, -3.72016840437287 - 10.90681139476287j,
         -3.72016840437287 + 10.90681139476287j, 0.16105338653172],
}  # fmt: skip


@pytest.fixture(scope="module")
def bicycle():
    bike, values, op = pfaff.models.whipple_bicycle()
    return bike, bike.equations(), values, op


def _lin(bicycle, v):
    bike, eom, _, op = bicycle
    return eom.linearize(op(v), bike.independent, bike.independent_speeds)


@pytest.mark.parametrize("v", sorted(TABLE2))
def test_eigenvalues_table2(bicycle, v: int) -> None:
    lin = _lin(bicycle, float(v))
    w = lean_steer_eigenvalues(lin)
    assert np.abs(w - np.array(TABLE2[v])).max() < 1e-10
    assert np.abs(w - meijaard_eigenvalues(v)).max() < 1e-11
    # the full spectrum: those four and six zeros (x, y, yaw, wheel angles, wheel rate)
    full = lin.eigenvalues()
    assert np.sort(np.abs(full))[:6].max() < 1e-9
    assert lin.is_stable() == (MEIJAARD_WEAVE_SPEED < v < MEIJAARD_CAPSIZE_SPEED)


def test_states_and_zero_columns(bicycle) -> None:
    bike, _, _, _ = bicycle
    lin = _lin(bicycle, 5.0)
    x, y, psi, phi, th_r, _, delta, th_f = bike.coordinates
    assert lin.states == [
        x,
        y,
        psi,
        phi,
        th_r,
        delta,
        th_f,
        *(q.diff() for q in (phi, th_r, delta)),
    ]
    A = lin.A
    for k in (0, 1, 4, 6):  # x, y and the wheel angles: zero columns, although x and θ rotate
        assert np.all(A[:, k] == 0)
    assert A[1, 2] == pytest.approx(5.0)  # ẏ = v ψ: the yaw column is not zero
    assert lin.ignorable() == [0, 1, 2, 4, 6, 8]
    C, D = lin.multipliers
    assert C.shape == (5, 10) and D.shape == (5, 0)
    # the front contact carries the weight the mass centres put on it (moments about the rear)
    p = bike.values
    front = p["g"] * (p["mB"] * p["xB"] + p["mH"] * p["xH"] + p["mF"] * p["w"]) / p["w"]
    assert lin.lambda0[0] == pytest.approx(-front, rel=1e-12)


def test_weave_and_capsize_speeds(bicycle) -> None:
    _, eom, _, _ = bicycle
    weave, capsize = stability_speeds(eom)
    assert weave == pytest.approx(MEIJAARD_WEAVE_SPEED, abs=1e-12)
    assert capsize == pytest.approx(MEIJAARD_CAPSIZE_SPEED, abs=1e-12)


def test_off_the_ground_is_refused(bicycle) -> None:
    bike, eom, _, op = bicycle
    point = op(5.0)
    point[bike.coordinates[5]] = 0.01  # pitched: the front wheel leaves the ground
    with pytest.raises(pfaff.ConstraintError, match="`front contact`"):
        eom.linearize(point, bike.independent, bike.independent_speeds)


def test_dependent_rates_are_computed(bicycle) -> None:
    """Only the rear wheel's rate given: ẋ, θ̇_F (dependent) follow from the constraints."""
    bike, eom, values, _ = bicycle
    point = {**dict.fromkeys(bike.coordinates, 0.0), **values}
    point[bike.coordinates[4].diff()] = -5.0 / values["rR"]
    lin = eom.linearize(point, bike.independent, bike.independent_speeds)
    np.testing.assert_allclose(lean_steer_eigenvalues(lin), TABLE2[5], atol=1e-10)


def test_compiled_model_linearize(bicycle) -> None:
    """NumericModel.linearize: the symbolic path's matrices and Table 2, by generated code."""
    from pfaff.models.bicycle import MEIJAARD, bicycle_state

    bike, eom, _, _ = bicycle
    model = eom.compile(MEIJAARD)
    ind = [str(c.func) for c in bike.independent]
    spd = [str(c.func) for c in bike.independent_speeds]
    for v in (2.0, 5.0, 8.0):
        lin = model.linearize(0.0, *bicycle_state(MEIJAARD, speed=v), ind, spd)
        np.testing.assert_allclose(lin.A, _lin(bicycle, v).A, rtol=1e-11, atol=1e-11)
        assert np.abs(lean_steer_eigenvalues(lin) - np.array(TABLE2[int(v)])).max() < 1e-10
