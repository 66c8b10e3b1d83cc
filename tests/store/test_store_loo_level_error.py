"""The level error of a joint left out (jointdb.store._loo._rel_error): the |ln| of the median ratio of predicted to
true storage and loss per diagonal DOF, over the lines where the true part is not near zero."""

from __future__ import annotations

import warnings

import numpy as np

from jointdb.store._loo import _rel_error


def _z(k, c, f):
    z = np.zeros((f.size, 2, 2), complex)
    z[:, 0, 0] = k[0] + 2j * np.pi * f * c[0]
    z[:, 1, 1] = k[1] + 2j * np.pi * f * c[1]
    return z


def test_the_level_error_is_the_log_ratio_of_the_parts():
    f = np.linspace(100.0, 2000.0, 50)
    got = _rel_error(_z((2e7, 4e4), (150.0, 0.6), f), _z((1e7, 5e4), (100.0, 0.5), f))
    np.testing.assert_allclose(got, np.abs(np.log([[2.0, 1.5], [0.8, 1.2]])), rtol=1e-12)


def test_a_joint_without_loss_gives_a_finite_error_and_no_warning():
    """A left-out joint whose loss is 0 on every line (an undamped spring) has no loss ratio: 0, not inf (the
    summary σ of the request built from it was NaN before)."""
    f = np.linspace(100.0, 2000.0, 50)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = _rel_error(_z((2e7, 4e4), (150.0, 0.6), f), _z((1e7, 5e4), (0.0, 0.5), f))
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got[:, 0], np.abs(np.log([2.0, 0.8])), rtol=1e-12)
    assert got[0, 1] == 0.0 and np.isclose(got[1, 1], np.log(1.2), rtol=1e-12)
