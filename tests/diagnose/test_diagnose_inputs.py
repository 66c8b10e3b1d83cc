"""Bad input gives clear messages (and the comparison helpers on known signatures)."""

import numpy as np
import pytest

from jointdb.diagnose import Measurement, diagnose, prepare
from jointdb.diagnose import find_peaks, pair_modes
from jointdb.diagnose_bench import generate_case
from jointdb.errors import InputError
from jointdb.fe import model_from_dict
from jointdb.frf import FRF, Dof


@pytest.fixture(scope="module")
def case():
    c = generate_case("none", 3)
    return c, model_from_dict(c.model)


def test_recordings_sharing_no_frequency_range(case):
    c, model = case
    frf = c.recordings[0].frf
    low = frf.band(None, 1000.0)
    high = frf.band(2000.0, None)
    with pytest.raises(InputError, match="share no frequency range"):
        diagnose(model, [Measurement(low, level=1.0), Measurement(high, level=2.0)])
    with pytest.raises(InputError, match="share no frequency range"):
        diagnose(model, [Measurement(frf)], band=(50000.0, 60000.0))


def test_recording_without_any_resonance_of_the_model(case):
    c, model = case
    frf = c.recordings[0].frf.band(60.0, 200.0)
    with pytest.raises(InputError, match="share no resonance"):
        diagnose(model, [Measurement(frf)])


def test_unmapped_dof_names_the_dof_and_the_fix(case):
    c, model = case
    frf = c.recordings[0].frf
    bad = FRF(frf.freq, frf.values, (Dof(7, "x"),) + frf.outputs[1:], frf.inputs, "receptance")
    with pytest.raises(InputError, match=r"output DOF 7x has no point in the model.*--map 7="):
        diagnose(model, [Measurement(bad)])
    # mapping it explicitly works for the preparation step
    obs = prepare(model, [Measurement(bad)], mapping={7: "tip"})
    assert obs.out_points[0] == "tip"
    with pytest.raises(InputError, match="no point 'nose'"):
        prepare(model, [Measurement(bad)], mapping={7: "nose"})


def test_direction_the_planar_model_lacks(case):
    c, model = case
    frf = c.recordings[0].frf
    bad = FRF(frf.freq, frf.values, (Dof(1, "y"),) + frf.outputs[1:], frf.inputs, "receptance")
    with pytest.raises(InputError, match="direction 'y'"):
        diagnose(model, [Measurement(bad)])


def test_no_usable_coherence(case):
    c, model = case
    r = c.recordings[0]
    with pytest.raises(InputError, match="no usable data"):
        diagnose(model, [Measurement(r.frf, coherence=np.full(r.frf.values.shape, 0.2), label="tap.uff")])
    with pytest.raises(InputError, match="coherence has shape"):
        diagnose(model, [Measurement(r.frf, coherence=np.ones((3, 3)))])


def test_levels_must_be_the_same_test(case):
    c, model = case
    frf = c.recordings[0].frf
    with pytest.raises(InputError, match="differ from the first recording"):
        diagnose(model, [Measurement(frf), Measurement(frf.select(outputs=frf.outputs[:2]))])


def test_peaks_and_pairing_on_a_known_two_mode_system():
    f = np.linspace(10, 400, 2000)
    w = 2 * np.pi * f

    def h(f1, f2, z):
        return (1 / ((2 * np.pi * f1) ** 2 - w**2 + 2j * z * 2 * np.pi * f1 * w)
                + 0.5 / ((2 * np.pi * f2) ** 2 - w**2 + 2j * z * 2 * np.pi * f2 * w))

    ones = np.ones((f.size, 1, 1))
    model = find_peaks(f, h(100, 300, 0.01)[:, None, None], ones)
    rec = find_peaks(f, h(95, 300, 0.02)[:, None, None], ones)
    assert [round(p.freq_hz) for p in model] == [100, 300]
    assert model[0].zeta == pytest.approx(0.01, rel=0.1)
    assert rec[0].zeta == pytest.approx(0.02, rel=0.1)
    pairs, extra, missing = pair_modes(model, rec)
    assert pairs == [(0, 0), (1, 1)] and extra == [] and missing == []
    assert rec[0].freq_hz / model[0].freq_hz - 1 == pytest.approx(-0.05, abs=0.003)


def test_signature_reads_gain_and_delay_from_the_data(case):
    from jointdb.diagnose import ModelEvaluator, signature

    c, model = case
    r = c.recordings[0]
    g, tau = 1.2, 40e-6
    chained = r.frf.replace(values=r.frf.values * g * np.exp(-2j * np.pi * r.frf.freq * tau)[:, None, None])
    obs = prepare(model, [Measurement(chained, r.coherence)])
    ev = ModelEvaluator(obs, full=True, method="direct")
    sig = signature(ev, ev.predict(model))
    assert sig.gain_db == pytest.approx(20 * np.log10(g), abs=0.3)
    assert sig.delay_s == pytest.approx(tau, rel=0.15)
    assert all(abs(p.shift) < 0.005 for p in sig.pairs)


# --------------------------------------------------------------- non-finite values and grids (issue 9, item 5)

def _with(frf, coherence=None, label="tap.uff", **edits):
    """The recording as arrays with some entries replaced: edits = {"values": [(line, out, in, value), ...]}."""
    freq, v = frf.freq.copy(), frf.values.copy()
    for k, o, i, x in edits.get("values", ()):
        v[k, o, i] = x
    for k, x in edits.get("freq", ()):
        freq[k] = x
    return Measurement.from_arrays(freq, v, frf.outputs, frf.inputs, coherence=coherence, label=label)


def test_a_nonfinite_value_is_refused_naming_file_entry_and_line(case):
    c, model = case
    r = c.recordings[0]
    m = _with(r.frf, r.coherence, values=[(100, 0, 0, np.inf)])
    f = r.frf.freq[100]
    msg = rf"tap\.uff: FRF 1x/1x: 1 non-finite value \(Inf\) at line 101 \({f:g} Hz\).*--mask-nonfinite"
    with pytest.raises(InputError, match=msg):
        prepare(model, [m])
    with pytest.raises(InputError, match=msg):
        diagnose(model, [m])
    m = _with(r.frf, values=[(7, 2, 1, np.nan), (8, 2, 1, np.nan), (9, 2, 1, np.nan), (300, 0, 1, np.nan)])
    with pytest.raises(InputError) as exc:
        prepare(model, [m])
    text = str(exc.value)
    assert "\n" not in text and "FRF 1x/2x: 1 non-finite value (NaN) at line 301" in text and "1 more FRF entry" in text


def test_masked_nonfinite_lines_get_zero_weight_and_a_note(case):
    c, model = case
    r = c.recordings[0]
    clean = prepare(model, [Measurement(r.frf, r.coherence, label="tap.uff")])
    m = _with(r.frf, r.coherence, values=[(100, 0, 0, np.inf), (101, 1, 0, np.nan), (102, 1, 0, np.nan)])
    obs = prepare(model, [m], mask_nonfinite=True)
    assert obs.full_weight[0, 100, 0, 0] == 0 and np.all(obs.full_weight[0, 101:103, 1, 0] == 0)
    keep = np.ones(obs.full_weight.shape, dtype=bool)
    keep[0, 100, 0, 0] = keep[0, 101:103, 1, 0] = False
    np.testing.assert_array_equal(obs.full_weight[keep], clean.full_weight[keep])   # nothing else changed
    assert np.all(np.isfinite(obs.full_values)) and np.all(np.isfinite(obs.values))
    assert obs.notes == ("tap.uff: 3 non-finite value(s) masked (zero weight): FRF 1x/1x at line 101 "
                         f"({r.frf.freq[100]:g} Hz); FRF 2x/1x at lines 102–103 "
                         f"({r.frf.freq[101]:g}–{r.frf.freq[102]:g} Hz)",)
    assert clean.notes == ()


def test_nonfinite_coherence_and_frequency_are_named(case):
    c, model = case
    r = c.recordings[0]
    coh = r.coherence.copy()
    coh[50, 2, 1] = np.nan
    with pytest.raises(InputError, match=r"tap\.uff: FRF 3x/2x: 1 non-finite coherence \(NaN\) at line 51"):
        prepare(model, [Measurement(r.frf, coh, label="tap.uff")])
    obs = prepare(model, [Measurement(r.frf, coh, label="tap.uff")], mask_nonfinite=True)
    assert obs.full_weight[0, 50, 2, 1] == 0 and "1 non-finite value(s) masked" in obs.notes[0]
    m = _with(r.frf, freq=[(40, np.nan)])
    with pytest.raises(InputError, match=r"tap\.uff: the frequency of line 41 is nan"):
        prepare(model, [m])
    obs = prepare(model, [m], mask_nonfinite=True)
    assert obs.full_freq.size == r.frf.n_freq - 1 and "non-finite frequency dropped (41)" in obs.notes[0]


def test_an_all_nan_frf_is_one_line_and_no_numpy_warning(case):
    import warnings

    c, model = case
    r = c.recordings[0]
    v = r.frf.values.copy()
    v[:, 2, 1] = np.nan
    m = Measurement.from_arrays(r.frf.freq, v, r.frf.outputs, r.frf.inputs, label="tap.uff")
    nan_all = Measurement.from_arrays(r.frf.freq, np.full(v.shape, np.nan), r.frf.outputs, r.frf.inputs,
                                      label="empty.uff")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError) as exc:
            diagnose(model, [m])
        assert str(exc.value).startswith("tap.uff: FRF 3x/2x: every value is non-finite (NaN/Inf)")
        assert "\n" not in str(exc.value)
        with pytest.raises(InputError, match=r"^empty\.uff: every value is non-finite \(NaN/Inf\); nothing"):
            prepare(model, [nan_all], mask_nonfinite=True)
        obs = prepare(model, [m], mask_nonfinite=True)
    clean = prepare(model, [Measurement(r.frf)])
    assert np.all(obs.full_weight[0, :, 2, 1] == 0)
    # the other five FRFs are used as without the NaN entry
    np.testing.assert_array_equal(obs.full_weight[0, :, :2], clean.full_weight[0, :, :2])
    np.testing.assert_array_equal(obs.full_weight[0, :, 2, 0], clean.full_weight[0, :, 2, 0])


def test_recordings_on_different_grids_say_what_was_dropped(case):
    c, model = case
    r = c.recordings[0]
    # the second level stops at 3000 Hz: the first loses its lines above, with the recorded 2nd mode (≈ 3969 Hz)
    short = r.frf.band(None, 3000.0)
    obs = prepare(model, [Measurement(r.frf, level=1.0, label="low.uff"), Measurement(short, level=2.0,
                                                                                      label="high.uff")])
    n_cut = int((r.frf.freq > 3000.0).sum())
    assert obs.full_freq[-1] == 3000.0
    assert len(obs.notes) == 1
    assert obs.notes[0].startswith(f"low.uff: {n_cut} line(s) above 3000 Hz dropped, outside the range all "
                                   "recordings share (5–3000 Hz), including recorded peak(s) at 39")
    # the second level on a grid half as fine, shifted by a quarter line: interpolated, and said so
    shifted = r.frf.resample(np.arange(r.frf.freq[0] + 2.5, r.frf.freq[-1], 10.0))
    obs = prepare(model, [Measurement(r.frf, level=1.0, label="low.uff"), Measurement(shifted, level=2.0,
                                                                                        label="high.uff")])
    assert any(n.startswith("high.uff: its ") and "interpolated linearly onto" in n and
               "coarser, so resonance peaks lose height" in n for n in obs.notes)
    assert any(n.startswith("low.uff: ") and "below 7.5 Hz" in n and "above" in n for n in obs.notes)
    # the same grid: no note
    same = prepare(model, [Measurement(r.frf, level=1.0), Measurement(r.frf, level=2.0)])
    assert same.notes == ()


def test_an_all_zero_frf_is_refused_in_one_line_without_a_numpy_warning(case):
    import warnings

    c, model = case
    r = c.recordings[0]
    v = r.frf.values.copy()
    v[:, 1, 0] = 0.0
    one = Measurement(FRF(r.frf.freq, v, r.frf.outputs, r.frf.inputs, "receptance"), label="tap.uff")
    every = Measurement(FRF(r.frf.freq, np.zeros_like(v), r.frf.outputs, r.frf.inputs, "receptance"),
                        label="dead.uff")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError) as exc:
            diagnose(model, [one])
        assert str(exc.value).startswith("tap.uff: FRF 2x/1x is exactly 0 at every line")
        assert "\n" not in str(exc.value)
        with pytest.raises(InputError, match=r"^dead\.uff: every FRF is exactly 0 at every line"):
            diagnose(model, [every])
        # a few exact zeros are a note (zero weight), not a refusal
        v[:, 1, 0] = r.frf.values[:, 1, 0]
        v[10, 1, 0] = 0.0
        obs = prepare(model, [Measurement(FRF(r.frf.freq, v, r.frf.outputs, r.frf.inputs, "receptance"))])
    assert any("exactly 0 get zero weight" in n for n in obs.notes)


def test_a_recording_above_what_a_beam_model_represents_is_refused_with_the_criterion():
    from jointdb.diagnose._validity import BEAM_WAVELENGTH_DIAMETERS, beam_limit_hz

    c = generate_case("interface_none", 0)
    model = model_from_dict(c.model)
    limit, where = beam_limit_hz(model)
    # the holder (⌀40–50 mm solid steel) sets it: the bending wavelength 2π (EI/ρA)^¼/√ω equals 4 D where
    # ω = (2π/(4D))² √(EI/ρA), with √(EI/ρA) = (D/4) √(E/ρ) for a solid section (≈ 12.7 kHz for D = 40 mm)
    d = float(where.split("⌀")[1].split(" mm")[0]) * 1e-3
    assert limit == pytest.approx((2 * np.pi / (BEAM_WAVELENGTH_DIAMETERS * d)) ** 2 * d / 4
                                  * np.sqrt(210e9 / 7850) / (2 * np.pi), rel=0.05)
    f = np.linspace(20000.0, 30000.0, 401)
    H = model.frf(f, points=["tip"], directions=["x"]).values
    with pytest.raises(InputError) as exc:
        diagnose(model, [Measurement(FRF(f, H, ("1x",), ("1x",), "receptance"), label="hf.uff")])
    text = str(exc.value)
    assert "\n" not in text and "20000–30000 Hz" in text and f"{limit:.0f} Hz" in text
    assert "bending wavelength" in text and "4 diameters" in text
