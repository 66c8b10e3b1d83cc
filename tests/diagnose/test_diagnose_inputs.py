"""Bad input gives clear messages (and the comparison helpers on known signatures)."""

import numpy as np
import pytest

from jointdb.diagnose import Measurement, diagnose, prepare
from jointdb.diagnose._compare import find_peaks, pair_modes
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
