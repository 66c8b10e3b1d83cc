"""Bad input to the coupling / identification API gives an InputError naming the problem (not a traceback)."""

import numpy as np
import pytest

from jointdb.coupling import (
    Interface,
    Regularisation,
    couple,
    equivalent_stiffness_damping,
    fit_constant_kc,
    identify_planar_joint,
    rotations_by_finite_difference,
    spring_damper_joint,
)
from jointdb.errors import InputError
from jointdb.frf import FRF

F = np.linspace(10.0, 100.0, 20)
J = spring_damper_joint(F, [1e6, 1e4], [10.0, 1.0], ["3x", "3ry"])


def test_kc_helpers_reject_non_frf_and_bad_masks():
    with pytest.raises(InputError, match="must be an FRF"):
        equivalent_stiffness_damping(np.ones((3, 2, 2)))
    with pytest.raises(InputError, match="must be an FRF"):
        fit_constant_kc(J.values)
    with pytest.raises(InputError, match=r"mask has shape \(5,\)"):
        fit_constant_kc(J, mask=np.ones(5, bool))


def test_regularisation_and_spring_inputs():
    with pytest.raises(InputError, match="'abc' is not a number"):
        Regularisation.parse("tikhonov:abc")
    with pytest.raises(InputError, match="1-D"):
        spring_damper_joint(np.ones((2, 2)), [1.0, 1.0], [1.0, 1.0], ["3x", "3ry"])


def test_interface_and_couple_inputs():
    with pytest.raises(InputError, match="listed twice"):
        Interface("A", ["3x", "3x"], "B", ["5x", "5ry"])
    with pytest.raises(InputError, match="mapping"):
        couple([J], [], [("A", "3x")])


def test_coincident_points_are_refused():
    h = FRF(F, np.ones((F.size, 2, 2)) * (1 - 1j), ("3x", "4x"), ("3x", "4x"))
    with pytest.raises(InputError, match="both node 3"):
        rotations_by_finite_difference(h, 3, 3, 0.01)
    with pytest.raises(InputError, match="both node 1"):
        identify_planar_joint(J, J, 3, J, 1, 1)


def test_binary_campaign_file_gives_one_input_error(tmp_path):
    from jointdb.campaign import load_campaign

    bad = tmp_path / "bad.json"
    bad.write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(InputError, match="not a UTF-8 text file"):
        load_campaign(bad)
