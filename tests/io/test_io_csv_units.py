"""CSV header units are honoured (issue 14: a `[mm/N]` file was read as m/N), through the
same unit table as UFF58 import; an unknown unit is refused with the known list."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.io import read_frf_csv, write_frf_csv


def _si_frf(quantity="receptance", outputs=("1x", "1ry"), inputs=("1x", "1ry")):
    f = np.linspace(10.0, 2000.0, 40)
    w = 2 * np.pi * f
    base = 1.0 / (1e7 * (1 - (w / (2 * np.pi * 900)) ** 2 + 0.04j * w / (2 * np.pi * 900)))
    vals = np.empty((f.size, len(outputs), len(inputs)), complex)
    for a in range(len(outputs)):
        for b in range(len(inputs)):
            vals[:, a, b] = base * (1 + a) * (2 + b)
    return FRF(f, vals, outputs, inputs, quantity)


def _rewrite(path, unit_of, scale_of, freq_header="freq [Hz]", freq_scale=1.0):
    """Rewrite an SI CSV with other header units; values divided by the factor to SI."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    new_header = [freq_header]
    for col in header[1:]:
        head, _ = col.split("[")
        entry = head.split()[1]
        new_header.append(f"{head}[{unit_of(entry)}]")
    rows = [new_header]
    for line in lines[1:]:
        nums = [float(x) for x in line.split(",")]
        row = [nums[0] / freq_scale]
        for k, col in enumerate(header[1:], start=1):
            row.append(nums[k] / scale_of(col.split()[1]))
        rows.append(row)
    out = path.with_name("converted.csv")
    out.write_text("\n".join(",".join(str(x) if isinstance(x, str) else repr(x) for x in r) for r in rows) + "\n")
    return out


def test_mm_per_n_and_khz_are_converted_to_si(tmp_path):
    frf = _si_frf()
    write_frf_csv(tmp_path / "si.csv", frf)
    # translations in mm/N, the rotation columns in mrad/(N*mm); the frequency in kHz
    units = {"1x/1x": ("mm/N", 1e-3), "1x/1ry": ("mm/(N*mm)", 1.0), "1ry/1x": ("mrad/N", 1e-3),
             "1ry/1ry": ("mrad/(N*mm)", 1.0)}
    path = _rewrite(tmp_path / "si.csv", lambda e: units[e][0], lambda e: units[e][1],
                    freq_header="freq [kHz]", freq_scale=1e3)
    got = read_frf_csv(path)
    np.testing.assert_allclose(got.freq, frf.freq, rtol=1e-12)
    # values went through a decimal print and one multiplication: a few ulp
    np.testing.assert_allclose(got.values, frf.values, rtol=1e-12, atol=0)
    # the raw numbers differ from the SI ones by the factor (so the test can fail)
    raw = float(path.read_text().splitlines()[1].split(",")[1])
    assert math.isclose(raw * 1e-3, got.values[0, 0, 0].real, rel_tol=1e-12)


def test_g_and_lbf_accelerance(tmp_path):
    frf = _si_frf("accelerance", ("1x",), ("1x",))
    write_frf_csv(tmp_path / "si.csv", frf)
    factor = 9.80665 / 4.4482216152605
    path = _rewrite(tmp_path / "si.csv", lambda e: "g/lbf", lambda e: factor)
    np.testing.assert_allclose(read_frf_csv(path).values, frf.values, rtol=1e-12)


@pytest.mark.parametrize("unit, needle", [
    ("furlong/N", "unknown response unit label 'furlong'; known: lengths m, mm"),
    ("mm/stone", "is not <response>/<excitation>"),
    ("mm/s/N", "is a velocity but the data-type code says receptance"),
    ("mrad/N", "is rotational but DOF 1x is not"),
])
def test_unknown_or_contradicting_units_are_refused(tmp_path, unit, needle):
    frf = _si_frf(outputs=("1x",), inputs=("1x",))
    write_frf_csv(tmp_path / "si.csv", frf)
    path = _rewrite(tmp_path / "si.csv", lambda e: unit, lambda e: 1.0)
    with pytest.raises(InputError, match="converted.csv: column 2") as exc:
        read_frf_csv(path)
    assert needle in str(exc.value)


def test_re_and_im_with_different_units_are_refused(tmp_path):
    write_frf_csv(tmp_path / "si.csv", _si_frf(outputs=("1x",), inputs=("1x",)))
    path = tmp_path / "si.csv"
    lines = path.read_text().splitlines()
    lines[0] = lines[0].replace("Im 1x/1x receptance [m/N]", "Im 1x/1x receptance [mm/N]")
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match="state different units"):
        read_frf_csv(path)


def test_unknown_frequency_unit_is_refused(tmp_path):
    write_frf_csv(tmp_path / "si.csv", _si_frf(outputs=("1x",), inputs=("1x",)))
    path = _rewrite(tmp_path / "si.csv", lambda e: "m/N", lambda e: 1.0, freq_header="freq [rpm]")
    with pytest.raises(InputError, match=r"not a frequency unit; known: Hz, 1/s, kHz"):
        read_frf_csv(path)


def test_lobes_from_a_mm_per_n_csv_equal_the_si_ones(tmp_path):
    """The user-visible symptom: lobes from a [mm/N] file were 1000x too shallow."""
    frf = _si_frf(outputs=("1x",), inputs=("1x",))
    write_frf_csv(tmp_path / "si.csv", frf)
    mm = _rewrite(tmp_path / "si.csv", lambda e: "mm/N", lambda e: 1e-3)
    args = ["lobes", "--op", "turning", "--kf", "1e9", "--json"]
    depths = []
    for p in (tmp_path / "si.csv", mm):
        r = subprocess.run([sys.executable, "-m", "jointdb", *args[:1], str(p), *args[1:]],
                           capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        depths.append(_numbers(json.loads(r.stdout)))
    assert len(depths[0]) == len(depths[1]) > 10
    # the same FRF up to a decimal print and one scaling: equal to ~1e-12 relative
    np.testing.assert_allclose(depths[1], depths[0], rtol=1e-9)


def _numbers(obj):
    if isinstance(obj, dict):
        return [x for k in sorted(obj) for x in _numbers(obj[k])]
    if isinstance(obj, list):
        return [x for v in obj for x in _numbers(v)]
    return [float(obj)] if isinstance(obj, (int, float)) and not isinstance(obj, bool) else []
