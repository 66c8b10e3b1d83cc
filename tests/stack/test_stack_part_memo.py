"""The memo of the parts' free receptances (jointdb/stack/_partcache.py) and the closed-form 2×2 matrix
exponential of the band's joint-choice draws (jointdb/stack/_band.py): both must give what they replace."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

from jointdb.stack import _partcache, stack_from_dict, stack_parts
from jointdb.stack._band import _expm

ROOT = Path(__file__).resolve().parents[2]
FREQ = np.arange(100.0, 4000.0, 25.0)


def _spec(gauge=0.05, spindle_k=3e8):
    spindle = {"segments": [{"length": 0.2, "outer_diameter": 0.07, "material": "steel"}],
               "points": [{"name": "nose", "position": 0.0, "node": 5}],
               "supports": [{"position": 0.15, "stiffness": {"x": spindle_k, "ry": 1e6}}], "clamps": [{"position": 0.2}]}
    return stack_from_dict({"name": "memo", "gauge_length": gauge,
                            "tool": {"material": "carbide", "segments": [{"length": 0.09, "diameter": 0.012}]},
                            "holder": {"material": "steel", "segments": [
                                {"length": 0.04, "outer_diameter": 0.032, "inner_diameter": 0.012},
                                {"length": 0.03, "outer_diameter": 0.05}]},
                            "spindle": {"point": "nose", "model": spindle},
                            "interfaces": {"tool-holder": "rigid", "holder-spindle": "rigid"}})


def _uncached(spec):
    _partcache.clear_part_cache()
    try:
        saved, _partcache.MAX_ENTRIES = _partcache.MAX_ENTRIES, 0
        return stack_parts(spec, FREQ)
    finally:
        _partcache.MAX_ENTRIES = saved


def test_memo_gives_the_same_parts_and_follows_every_edit():
    _partcache.clear_part_cache()
    first = stack_parts(_spec(), FREQ)
    again = stack_parts(_spec(), FREQ)          # equal content, new objects: kept FRFs
    assert all(again[k] is first[k] for k in first)
    for k in first:                             # what the memo returns is what a fresh build gives
        np.testing.assert_array_equal(first[k].values, _uncached(_spec())[k].values)
    _partcache.clear_part_cache()
    stack_parts(_spec(), FREQ)
    longer = stack_parts(_spec(gauge=0.06), FREQ)      # the tool (and holder key) changed
    softer = stack_parts(_spec(spindle_k=1e8), FREQ)   # only the spindle model changed
    base = _uncached(_spec())
    assert not np.allclose(longer["tool"].values, base["tool"].values)
    np.testing.assert_array_equal(longer["tool"].values, _uncached(_spec(gauge=0.06))["tool"].values)
    np.testing.assert_array_equal(softer["tool"].values, base["tool"].values)
    assert not np.allclose(softer["spindle"].values, base["spindle"].values)
    np.testing.assert_array_equal(softer["spindle"].values, _uncached(_spec(spindle_k=1e8))["spindle"].values)
    other_grid = stack_parts(_spec(), FREQ[::2])
    assert other_grid["tool"].values.shape[0] == FREQ[::2].size


def test_kept_arrays_are_read_only_and_the_memo_is_bounded():
    _partcache.clear_part_cache()
    parts = stack_parts(_spec(), FREQ)
    with pytest.raises(ValueError):
        parts["tool"].values[0, 0, 0] = 0.0
    for k in range(_partcache.MAX_ENTRIES):
        stack_parts(_spec(gauge=0.05 + 1e-4 * k), FREQ)
    assert len(_partcache._memo) <= _partcache.MAX_ENTRIES


def test_a_spindle_model_given_as_a_path_is_not_kept():
    assert _partcache.spindle_key("spindles/x.json") is None
    assert _partcache.spindle_key({"a": [1, 2]}) == _partcache.spindle_key({"a": [1, 2]})
    assert _partcache.spindle_key({"a": [1, 2]}) != _partcache.spindle_key({"a": [1, 3]})


def test_closed_form_exponential_of_2x2_blocks_equals_scipy():
    rng = np.random.default_rng(7)
    cases = [rng.normal(size=(50, 2, 2)) * s + 1j * rng.normal(size=(50, 2, 2)) * s for s in (1e-5, 0.1, 1.0, 3.0)]
    nil = np.array([[[0, 1.0], [0, 0]], [[2.0, 5.0], [0, 2.0]], [[1.5, 0], [0, 1.5]], [[0, 0], [0, 0]]], dtype=complex)
    near = np.array([[[1.0, 1e-4], [1e-4, 1.0 + 1e-4]], [[0.3j, 1e-3], [-1e-3, 0.3j]]], dtype=complex)
    for a in (*cases, nil, near):
        want = np.stack([expm(m) for m in a])
        got = _expm(a)
        scale = np.linalg.norm(want, axis=(-2, -1))[:, None, None]
        assert np.max(np.abs(got - want) / scale) < 1e-12
    a = rng.normal(size=(3, 4, 3, 3)) + 0j      # other sizes go to scipy
    np.testing.assert_allclose(_expm(a), expm(a), rtol=1e-12)


def test_the_closed_form_falls_back_where_cosh_overflows():
    """cosh √q overflows for |√q| > ~710 while e^μ brings exp A back to finite values: scipy's scaling and squaring."""
    a = np.array([[[-800.0, 800.0], [800.0, -800.0]]], dtype=complex)
    np.testing.assert_allclose(_expm(a), expm(a[0])[None], rtol=1e-12)
    assert np.allclose(_expm(a), 0.5)
