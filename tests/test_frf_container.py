"""Tests of jointdb.frf: DOF labels, validation, exact quantity conversion, selection,
reciprocity completion, resampling, stacking; plus the import-layering check."""

import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jointdb.errors import InputError
from jointdb.frf import DIRECTIONS, FRF, Dof, Quantity, dofs


def sdof(freq, k=1e6, m=1.0, c=20.0):
    """Analytic receptance, mobility, accelerance of a spring-mass-damper (x = X e^{+iωt})."""
    w = 2 * np.pi * np.asarray(freq, dtype=float)
    h = 1.0 / (k - m * w**2 + 1j * c * w)
    return h, 1j * w * h, -(w**2) * h


def frf_2x3(freq=None, quantity="receptance", seed=0):
    freq = np.arange(1.0, 21.0) if freq is None else freq
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(len(freq), 2, 3)) + 1j * rng.normal(size=(len(freq), 2, 3))
    return FRF(freq, v, ("1x", "2y"), ("1x", "3z", "4rx"), quantity)


# ------------------------------------------------------------------ Dof
@pytest.mark.parametrize("text, dof", [
    ("12x", Dof(12, "x")), ("12:rx", Dof(12, "rx")), ("12 RX", Dof(12, "rx")), (" 3.ry ", Dof(3, "ry")),
    ((4, "Z"), Dof(4, "z")), (Dof(5, "y"), Dof(5, "y")), ("0rz", Dof(0, "rz")),
])
def test_dof_parse(text, dof):
    assert Dof.parse(text) == dof


@pytest.mark.parametrize("text", ["x12", "12", "12w", "-3x", "12-x", "", "1.5x", 5])
def test_dof_parse_refuses(text):
    with pytest.raises(InputError):
        Dof.parse(text)


def test_dof_validation_and_codes():
    with pytest.raises(InputError):
        Dof(1, "q")
    with pytest.raises(InputError):
        Dof(-1, "x")
    with pytest.raises(InputError):
        Dof(True, "x")
    with pytest.raises(InputError):
        Dof(1.0, "x")
    assert Dof(np.int64(7), "X") == Dof(7, "x") and type(Dof(np.int64(7), "x").node) is int
    assert [Dof(1, d).uff_code for d in DIRECTIONS] == [1, 2, 3, 4, 5, 6]
    assert [Dof(1, d).is_rotation for d in DIRECTIONS] == [False] * 3 + [True] * 3
    assert str(Dof(12, "rx")) == "12rx"
    assert Dof.from_uff(3, -5) == (Dof(3, "ry"), -1) and Dof.from_uff(3, 2) == (Dof(3, "y"), 1)
    for bad in (0, 7, -7):
        with pytest.raises(InputError):
            Dof.from_uff(1, bad)
    assert dofs("3x") == (Dof(3, "x"),) and dofs(["1x", (2, "y")]) == (Dof(1, "x"), Dof(2, "y"))
    assert sorted([Dof(2, "x"), Dof(1, "y"), Dof(1, "x")]) == [Dof(1, "x"), Dof(1, "y"), Dof(2, "x")]


def test_quantity_parse():
    assert Quantity.parse("Mobility") is Quantity.MOBILITY
    assert Quantity.parse(Quantity.ACCELERANCE) is Quantity.ACCELERANCE
    assert [q.power for q in Quantity] == [0, 1, 2]
    with pytest.raises(InputError):
        Quantity.parse("inertance")


# ------------------------------------------------------------------ validation
@pytest.mark.parametrize("freq, values, outputs, inputs, fragment", [
    ([], np.zeros((0, 1, 1)), ["1x"], ["1x"], "non-empty"),
    ([[1.0, 2.0]], np.zeros((2, 1, 1)), ["1x"], ["1x"], "1-D"),
    ([1.0, np.nan], np.zeros((2, 1, 1)), ["1x"], ["1x"], "NaN"),
    ([1.0, np.inf], np.zeros((2, 1, 1)), ["1x"], ["1x"], "inf"),
    ([-1.0, 2.0], np.zeros((2, 1, 1)), ["1x"], ["1x"], ">= 0"),
    ([1.0, 1.0], np.zeros((2, 1, 1)), ["1x"], ["1x"], "strictly increasing"),
    ([2.0, 1.0], np.zeros((2, 1, 1)), ["1x"], ["1x"], "strictly increasing"),
    ([1.0, 2.0], np.zeros((2, 1)), ["1x"], ["1x"], r"shape \(2, 1\)"),
    ([1.0, 2.0], np.zeros((2, 2, 1)), ["1x"], ["1x"], r"expected .* \(2, 1, 1\)"),
    ([1.0, 2.0], np.zeros(2), ["1x", "2x"], ["1x"], "shape"),
    ([1.0, 2.0], np.array([1, np.nan])[:, None, None], ["1x"], ["1x"], "1 NaN or inf"),
    ([1.0, 2.0], np.full((2, 1, 1), np.inf * 1j), ["1x"], ["1x"], "2 NaN or inf"),
    ([1.0, 2.0], np.zeros((2, 2, 1)), ["1x", "1x"], ["1x"], "duplicate output DOF 1x"),
    ([1.0, 2.0], np.zeros((2, 1, 2)), ["1x"], ["2y", "2Y"], "duplicate input DOF 2y"),
    ([1.0, 2.0], np.zeros((2, 0, 1)), [], ["1x"], "at least one output"),
    ([1.0, 2.0], np.zeros((2, 1, 1)), ["1w"], ["1x"], "1w"),
])
def test_validation_errors(freq, values, outputs, inputs, fragment):
    with pytest.raises(InputError, match=fragment) as e:
        FRF(freq, values, outputs, inputs)
    assert "\n" not in str(e.value)


def test_unknown_quantity_is_refused():
    with pytest.raises(InputError, match="unknown FRF quantity"):
        FRF([1.0], [1.0], ["1x"], ["1x"], "compliance")


def test_frf_copies_and_freezes_its_arrays():
    freq = np.array([1.0, 2.0])
    vals = np.ones((2, 1, 1), dtype=complex)
    h = FRF(freq, vals, ["1x"], ["1x"])
    freq[0] = 0.5
    vals[0] = 7.0
    assert h.freq[0] == 1.0 and h.values[0, 0, 0] == 1.0
    with pytest.raises(ValueError):
        h.values[0, 0, 0] = 3.0
    with pytest.raises(ValueError):
        h.freq[0] = 3.0
    assert h.values.dtype == np.complex128 and h.freq.dtype == np.float64
    one = FRF([1.0, 2.0], [1.0, 2.0], "1x", "2y")  # 1-D values for a single pair
    assert one.shape == (2, 1, 1) and one.outputs == (Dof(1, "x"),)


def test_replace_revalidates():
    h = frf_2x3()
    with pytest.raises(InputError):
        h.replace(values=h.values[:, :1])
    assert h.replace(quantity="mobility").quantity is Quantity.MOBILITY


# ------------------------------------------------------------------ conversions
def test_quantity_conversion_matches_analytic_sdof():
    f = np.linspace(1.0, 400.0, 500)
    h, y, a = sdof(f)
    rec = FRF(f, h, ["1x"], ["1x"], "receptance")
    mob = FRF(f, y, ["1x"], ["1x"], "mobility")
    acc = FRF(f, a, ["1x"], ["1x"], "accelerance")
    tol = 1e-14
    assert rec.to("mobility").allclose(mob, rtol=tol)
    assert rec.to("accelerance").allclose(acc, rtol=tol)
    assert mob.to("receptance").allclose(rec, rtol=tol)
    assert acc.to("receptance").allclose(rec, rtol=tol)
    assert acc.to("mobility").allclose(mob, rtol=tol)
    assert mob.to("accelerance").allclose(acc, rtol=tol)
    assert rec.to("receptance") is rec


def test_conversion_factors_are_exactly_i_omega_powers():
    f = np.array([0.5, 3.0, 10.0])
    rec = FRF(f, np.ones(3, complex), ["1x"], ["1x"])
    w = 2 * np.pi * f
    assert np.array_equal(rec.to("mobility").values[:, 0, 0], 1j * w)
    assert np.array_equal(rec.to("accelerance").values[:, 0, 0], (1j * w) ** 2)
    assert np.array_equal(rec.omega, w)


def test_conversion_at_zero_hz():
    f = np.array([0.0, 1.0, 2.0])
    rec = FRF(f, np.ones(3, complex), ["1x"], ["1x"])
    assert rec.to("accelerance").values[0, 0, 0] == 0  # multiplying by (iω)^2 is fine at 0 Hz
    for src, dst in [("mobility", "receptance"), ("accelerance", "receptance"), ("accelerance", "mobility")]:
        with pytest.raises(InputError, match="0 Hz") as e:
            rec.replace(quantity=src).to(dst)
        assert "band" in str(e.value)
    assert rec.replace(quantity="accelerance").band(fmin=0.5).to("receptance").n_freq == 2


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.01, 1e5), min_size=1, max_size=30, unique=True),
       st.sampled_from(list(Quantity)), st.sampled_from(list(Quantity)))
def test_property_conversion_round_trip(freqs, q1, q2):
    f = np.sort(np.array(freqs))
    rng = np.random.default_rng(len(freqs))
    h = FRF(f, rng.normal(size=f.size) + 1j * rng.normal(size=f.size), ["1x"], ["1x"], q1)
    back = h.to(q2).to(q1)
    assert back.quantity is q1
    assert np.allclose(back.values, h.values, rtol=1e-13, atol=0)


# ------------------------------------------------------------------ selection
def test_select_block_entry():
    h = frf_2x3()
    s = h.select(outputs=["2y"], inputs=["4rx", "1x"])
    assert s.outputs == (Dof(2, "y"),) and s.inputs == (Dof(4, "rx"), Dof(1, "x"))
    assert np.array_equal(s.values[:, 0, 0], h.values[:, 1, 2])
    assert np.array_equal(s.values[:, 0, 1], h.values[:, 1, 0])
    assert np.array_equal(h.block(["1x", "2y"], ["3z"]), h.values[:, :, 1:2])
    assert np.array_equal(h.entry("2y", "3z"), h.values[:, 1, 1])
    assert np.array_equal(h.entry(Dof(2, "y"), (3, "z")), h.values[:, 1, 1])
    assert h.select().allclose(h, rtol=0)
    assert h.select(inputs="3z").shape == (20, 2, 1)
    with pytest.raises(InputError, match=r"output DOF 9x is not in this FRF \(it has: 1x 2y\)"):
        h.select(outputs=["9x"])
    with pytest.raises(InputError, match="input DOF 1y"):
        h.entry("1x", "1y")


def test_band():
    h = frf_2x3()
    b = h.band(5.0, 8.0)
    assert np.array_equal(b.freq, [5.0, 6.0, 7.0, 8.0]) and np.array_equal(b.values, h.values[4:8])
    assert h.band(fmax=2.0).n_freq == 2 and h.band(fmin=20.0).n_freq == 1
    with pytest.raises(InputError, match="no frequency lines"):
        h.band(30.0, 40.0)


@settings(max_examples=30, deadline=None)
@given(st.permutations(["1x", "2y"]), st.permutations(["1x", "3z", "4rx"]), st.integers(1, 3))
def test_property_select_is_consistent_with_values(outs, ins, n_in):
    h = frf_2x3()
    s = h.select(outs, ins[:n_in])
    for a, o in enumerate(outs):
        for b, i in enumerate(ins[:n_in]):
            assert np.array_equal(s.values[:, a, b], h.entry(o, i))


# ------------------------------------------------------------------ reciprocity
def symmetric_frf(n=4, n_freq=6, seed=0):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n_freq, n, n)) + 1j * rng.normal(size=(n_freq, n, n))
    a = a + np.swapaxes(a, 1, 2)
    labels = tuple(Dof(k + 1, "x") for k in range(n))
    return FRF(np.arange(1.0, n_freq + 1), a, labels, labels)


def test_complete_reciprocal_reorders_onto_the_union_and_keeps_measured_entries():
    full = symmetric_frf(3, seed=2)
    v = full.values.copy()
    v[:, 0, 1] += 0.5  # H[1x,2x] != H[2x,1x]: both are kept as measured, not symmetrised
    meas = FRF(full.freq, v, full.outputs, full.inputs)
    shuffled = meas.select(inputs=["3x", "1x", "2x"])
    sq = shuffled.complete_reciprocal()
    assert sq.outputs == sq.inputs == (Dof(1, "x"), Dof(2, "x"), Dof(3, "x"))
    assert np.array_equal(sq.values, meas.values)
    assert sq.reciprocity_error() > 0


@pytest.mark.parametrize("outs, ins, missing", [
    (["1x"], ["1x", "2x", "3x"], r"H\[2x, 2x\]"),            # a row: the other driving points are unknown
    (["1x", "2x", "3x"], ["1x"], r"H\[2x, 2x\]"),            # a column
    (["1x", "2x"], ["1x", "2x", "3x"], r"H\[3x, 3x\]"),
])
def test_complete_reciprocal_names_an_entry_it_cannot_know(outs, ins, missing):
    full = symmetric_frf(3, seed=4)
    with pytest.raises(InputError, match=missing + ".*known neither directly nor by reciprocity"):
        full.select(outs, ins).complete_reciprocal()


def test_complete_reciprocal_turns_a_measured_row_into_a_column():
    full = symmetric_frf(3, seed=6)
    row = full.select(["1x"], ["1x", "2x", "3x"])
    col = row.complete_reciprocal(outputs=["1x", "2x", "3x"], inputs=["1x"])
    assert np.array_equal(col.values, full.select(["1x", "2x", "3x"], ["1x"]).values)


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 5), st.integers(0, 2**31))
def test_property_complete_reciprocal_of_a_permuted_square_set(n, seed):
    full = symmetric_frf(n, seed=seed % 1000)
    rng = np.random.default_rng(seed)
    outs = [full.outputs[k] for k in rng.permutation(n)]
    ins = [full.inputs[k] for k in rng.permutation(n)]
    sq = full.select(outs, ins).complete_reciprocal()
    assert sq.outputs == tuple(outs) and sq.inputs == tuple(outs)
    assert np.array_equal(sq.values, full.block(outs, outs))
    assert sq.reciprocity_error() == 0.0


def test_reciprocity_error():
    full = symmetric_frf(3)
    assert full.reciprocity_error() == 0.0
    v = full.values.copy()
    v[:, 0, 2] *= 1.01
    assert 0 < FRF(full.freq, v, full.outputs, full.inputs).reciprocity_error() < 0.05
    assert frf_2x3().select(["1x"], ["1x"]).reciprocity_error() == 0.0


# ------------------------------------------------------------------ resampling
def test_resample_is_exact_for_linear_data_and_on_the_same_grid():
    f = np.linspace(10.0, 100.0, 10)
    v = (2.0 + 3.0j) * f - 1.0j
    h = FRF(f, v, ["1x"], ["1x"])
    new = np.linspace(10.0, 100.0, 37)
    r = h.resample(new)
    assert np.allclose(r.values[:, 0, 0], (2.0 + 3.0j) * new - 1.0j, rtol=1e-14, atol=0)
    assert np.array_equal(h.resample(f).values, h.values)
    sub = h.resample(f[2:7])
    assert np.array_equal(sub.values, h.values[2:7])


@pytest.mark.parametrize("new", [[5.0, 50.0], [10.0, 100.5], [0.0], [200.0]])
def test_resample_refuses_to_extrapolate(new):
    h = FRF(np.linspace(10.0, 100.0, 10), np.ones(10, complex), ["1x"], ["1x"])
    with pytest.raises(InputError, match="extrapolate"):
        h.resample(new)


def test_resample_bad_grids():
    h = FRF(np.linspace(10.0, 100.0, 10), np.ones(10, complex), ["1x"], ["1x"])
    with pytest.raises(InputError):
        h.resample([])
    with pytest.raises(InputError, match="strictly increasing"):
        h.resample([50.0, 20.0])
    # a grid end within round-off of the measured end is accepted (clipped), not extrapolated
    assert h.resample([10.0, 100.0 * (1 + 1e-13)]).freq[-1] == 100.0


@settings(max_examples=30, deadline=None)
@given(st.integers(3, 60), st.integers(0, 2**31))
def test_property_resample_onto_a_subset_of_the_grid_is_exact(n, seed):
    rng = np.random.default_rng(seed)
    f = np.cumsum(rng.uniform(0.1, 5.0, n))
    h = FRF(f, rng.normal(size=(n, 2, 2)) + 1j * rng.normal(size=(n, 2, 2)), ["1x", "2x"], ["1x", "2x"])
    idx = np.sort(rng.choice(n, size=max(1, n // 2), replace=False))
    r = h.resample(f[idx])
    assert np.array_equal(r.values, h.values[idx])


# ------------------------------------------------------------------ stacking and misc
def test_concat_outputs_and_inputs():
    h = frf_2x3()
    a = h.select(["1x"])
    b = h.select(["2y"])
    assert np.array_equal(FRF.concat_outputs([a, b]).values, h.values)
    c = h.select(inputs=["1x"])
    d = h.select(inputs=["3z", "4rx"])
    assert np.array_equal(FRF.concat_inputs([c, d]).values, h.values)
    with pytest.raises(InputError, match="share"):
        FRF.concat_outputs([a, b.replace(quantity="mobility")])
    with pytest.raises(InputError, match="share"):
        FRF.concat_inputs([c, d.band(fmax=5.0)])
    with pytest.raises(InputError, match="duplicate output"):
        FRF.concat_outputs([a, a])


def test_concat_of_nothing_is_an_input_error():
    with pytest.raises(InputError):
        FRF.concat_outputs([])


def test_dof_parse_of_a_bad_tuple_is_an_input_error():
    with pytest.raises(InputError):
        Dof.parse(("a", "x"))


def test_allclose_and_repr():
    h = frf_2x3()
    assert h.allclose(h.replace())
    assert not h.allclose(h.replace(quantity="mobility"))
    assert not h.allclose(h.select(["2y", "1x"]))
    assert not h.allclose(h.replace(values=h.values * (1 + 1e-6)))
    assert "receptance" in repr(h) and "1x 2y" in repr(h)


def test_import_jointdb_frf_pulls_in_no_io_or_ui_library():
    heavy = ["sqlalchemy", "h5py", "typer", "matplotlib", "pyuff"]
    code = f"import sys, jointdb.frf; print(','.join(m for m in {heavy!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_complete_reciprocal_to_targets_names_what_cannot_be_known():
    full = symmetric_frf(3, seed=7)
    row = full.select(["1x"], ["1x", "2x", "3x"])
    with pytest.raises(InputError, match=r"H\[2x, 3x\]"):
        row.complete_reciprocal(outputs=["1x", "2x"], inputs=["3x"])
    both = row.complete_reciprocal(outputs=["2x", "1x"], inputs=["1x"])
    assert np.array_equal(both.values[:, :, 0], np.stack([full.entry("1x", "2x"), full.entry("1x", "1x")], 1))
