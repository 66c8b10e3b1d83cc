"""Fuzz corpus: bad command-line arguments of the non-store commands, with valid input files.

jointdb's own checks must give one ``error:`` line, exit 2 (3 for a missing
file) and write nothing. Usage errors that Typer/Click detect while parsing
(an integer option given text, an unknown option) are reported by Click in
its own multi-line format; those are checked separately for exit 2, no
traceback and nothing written.
"""

from __future__ import annotations

import shutil

import pytest
from fuzz_helpers import (
    INPUT,
    MODEL_FIXTURE,
    NOT_FOUND,
    STACK_FIXTURE,
    Case,
    check_case,
    copy_campaign,
    run_main,
    seed_bytes,
    snapshot,
)

VALID = {"m.json": MODEL_FIXTURE.read_text(), "s.json": STACK_FIXTURE.read_text()}


def _with_frf(files=None):
    out = dict(VALID)
    out["tip.h5"] = seed_bytes("h5")
    out["tip.uff"] = seed_bytes("uff")
    out.update(files or {})
    return out


def _cases() -> list[Case]:
    c = []

    def add(cid, args, match=None, codes=(INPUT,), files=None):
        c.append(Case(f"{args[0]}-{cid}", list(args), _with_frf(files), codes, match))

    # modes / frf
    add("n-zero", ["modes", "m.json", "--n", "0"], "--n")
    add("n-negative", ["modes", "m.json", "--n", "-5"], "--n")
    frf = ["frf", "m.json", "--out", "o.h5"]
    add("fmax-nan", [*frf, "--fmax", "nan"], "--fmax")
    add("fmax-inf", [*frf, "--fmax", "inf"], "--fmax")
    add("fmax-negative", [*frf, "--fmax", "-1"], "--fmax")
    add("fmin-above-fmax", [*frf, "--fmin", "6000"], "--fmin")
    add("fmin-nan", [*frf, "--fmin", "nan"], "--fmin")
    add("df-zero", [*frf, "--df", "0"], "--df")
    add("df-tiny", [*frf, "--df", "1e-9"], "--df")
    add("df-nan", [*frf, "--df", "nan"], "--df")
    add("n-lines-one", [*frf, "--n-lines", "1"], "--n-lines")
    add("n-lines-huge", [*frf, "--n-lines", "1000000000"], "--n-lines")
    add("df-and-n-lines", [*frf, "--df", "1", "--n-lines", "10"], "--df")
    add("points-unknown", [*frf, "--points", "nosuch"], "nosuch")
    add("points-empty", [*frf, "--points", ","], "empty")
    add("directions-unknown", [*frf, "--directions", "q"], "q")
    add("method-unknown", [*frf, "--method", "magic"], "magic")
    add("quantity-unknown", [*frf, "--quantity", "force"], "force")
    add("out-suffix", ["frf", "m.json", "--out", "o.txt"], "o.txt")
    add("out-missing-dir", ["frf", "m.json", "--out", "nodir/o.h5"], "nodir")
    add("plot-suffix", ["frf", "m.json", "--plot", "p.jpg"], "p.jpg")
    add("n-modes-zero", [*frf, "--method", "modal", "--n-modes", "0"], "mode")
    # lobes
    lobes = ["lobes", "tip.h5", "--plot", "l.png"]
    mill = ["--kt", "6e8", "--kr", "2e8"]
    add("op-unknown", [*lobes, "--op", "drill"], "--op")
    add("method-unknown", [*lobes, *mill, "--method", "magic"], "--method")
    add("speeds-one", [*lobes, *mill, "--n-speeds", "1"], "--n-speeds")
    add("speeds-huge", [*lobes, *mill, "--n-speeds", "1000000000"], "--n-speeds")
    add("teeth-zero", [*lobes, *mill, "--teeth", "0"], "teeth")
    add("teeth-huge", [*lobes, *mill, "--teeth", "1000000"], "--teeth")
    add("kt-nan", [*lobes, "--kt", "nan", "--kr", "2e8"], "--kt")
    add("kt-negative", [*lobes, "--kt", "-1", "--kr", "2e8"], "kt")
    add("kt-missing", [*lobes, "--kr", "2e8"], "--kt")
    add("immersion-two", [*lobes, *mill, "--immersion", "2"], "immersion")
    add("immersion-zero", [*lobes, *mill, "--immersion", "0"], "immersion")
    add("rpm-negative", [*lobes, *mill, "--rpm-min", "-1"], "--rpm-min")
    add("rpm-inf", [*lobes, *mill, "--rpm-max", "inf"], "--rpm")
    add("turning-no-kf", [*lobes, "--op", "turning"], "--kf")
    add("turning-orientation-text", [*lobes, "--op", "turning", "--kf", "1e9", "--orientation", "a,b"],
        "--orientation")
    add("node-absent", [*lobes, *mill, "--node", "99"], "--node")
    add("intervals-one", [*lobes, *mill, "--method", "sd", "--intervals", "1"], "--intervals")
    add("intervals-huge", [*lobes, *mill, "--method", "sd", "--intervals", "10000000"], "--intervals")
    add("max-order-huge", [*lobes, *mill, "--method", "sd", "--max-order", "1000000"], "--max-order")
    add("plot-missing-dir", ["lobes", "tip.h5", *mill, "--plot", "nodir/l.png"], "nodir")
    add("plots-missing-parent", ["lobes", "tip.h5", *mill, "--plots", "nodir/figs"], "nodir")
    add("plots-is-a-file", ["lobes", "tip.h5", *mill, "--plots", "tip.h5"], "--plots")
    add("plots-and-plot", ["lobes", "tip.h5", *mill, "--plots", "figs", "--plot", "l.png"], "--plots")
    add("out-suffix", ["lobes", "tip.h5", *mill, "--out", "l.txt"], "l.txt")
    add("frf-y-missing", [*lobes, *mill, "--frf-y", "nothere.h5"], "nothere.h5", (NOT_FOUND,))
    add("frf-unknown-suffix", ["lobes", "tip.dat", *mill], "tip.dat", files={"tip.dat": b"1,2,3\n"})
    # modal-fit
    fit = ["modal-fit", "tip.uff", "--plot", "figs"]
    add("band-reversed", [*fit, "--band", "100", "10"], "--band")
    add("band-nan", [*fit, "--band", "nan", "10"], "--band")
    add("max-order-huge", [*fit, "--max-order", "1000000"], "--max-order")
    add("modes-huge", [*fit, "--modes", "100000"], "--modes")
    add("plot-is-a-file", ["modal-fit", "tip.uff", "--plot", "m.json"], "m.json")
    # predict
    pred = ["predict", "s.json", "--out", "tip-out.h5"]
    add("fmin-negative", [*pred, "--fmin", "-1"], "--fmin")
    add("df-zero", [*pred, "--df", "0"], "--df")
    add("df-tiny", [*pred, "--df", "1e-9"], "--df")
    add("fmax-nan", [*pred, "--fmax", "nan"], "--fmax")
    add("out-suffix", ["predict", "s.json", "--out", "tip.txt"], "tip.txt")
    add("out-missing-dir", ["predict", "s.json", "--out", "nodir/tip.h5"], "nodir")
    add("plot-missing-dir", ["predict", "s.json", "--plot", "nodir/p.png"], "nodir")
    add("plots-missing-parent", ["predict", "s.json", "--plots", "nodir/figs"], "nodir")
    add("stack-missing", ["predict", "nothere.json"], "nothere.json", (NOT_FOUND,))
    return c


def _campaign_cases() -> list[Case]:
    c = []

    def add(cid, args, match=None, codes=(INPUT,), files=None):
        f = {"__campaign__": True}
        f.update(files or {})
        c.append(Case(f"{args[0]}-{cid}", list(args), f, codes, match))

    add("out-suffix", ["identify", "campaign.json", "--out", "j.txt"], "j.txt")
    add("out-missing-dir", ["identify", "campaign.json", "--out", "nodir/j.h5"], "nodir")
    add("report-suffix", ["identify", "campaign.json", "--out", "j.h5", "--report", "r.txt"], "r.txt")
    add("plots-is-a-file", ["identify", "campaign.json", "--out", "j.h5", "--plots", "campaign.json"], "--plots")
    add("joint-missing", ["couple", "campaign.json", "--joint", "nothere.h5"], "nothere.h5", (NOT_FOUND,))
    add("out-suffix", ["couple", "campaign.json", "--out", "a.csv"], "a.csv")
    add("plot-suffix", ["couple", "campaign.json", "--plot", "a.jpg"], "a.jpg")
    add("joint-not-hdf5", ["couple", "campaign.json", "--joint", "campaign.json", "--out", "a.h5"], "campaign.json")
    return c


def _diagnose_cases() -> list[Case]:
    c = []
    files = _with_frf()

    def add(cid, args, match=None, codes=(INPUT,)):
        c.append(Case(f"diagnose-{cid}", ["diagnose", "m.json", "tip.uff", *args, "--out", "d.json"], files, codes,
                      match))

    add("map-garbage", ["--map", "garbage"], "--map")
    add("map-unknown-point", ["--map", "1=nosuch"], "nosuch")
    add("levels-text", ["--levels", "abc"], "--levels")
    add("levels-count", ["--levels", "1,2,3"], "--levels")
    add("band-text", ["--band", "a:b"], "--band")
    add("band-reversed", ["--band", "500:100"], "band")
    c.append(Case("diagnose-out-suffix-csv", ["diagnose", "m.json", "tip.uff", "--out", "d.csv"], files, (INPUT,),
                  "d.csv"))
    c.append(Case("diagnose-recording-missing", ["diagnose", "m.json", "nothere.uff"], files, (NOT_FOUND,),
                  "nothere.uff"))
    return c


CASES = _cases() + _campaign_cases()
DIAGNOSE = _diagnose_cases()


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_argument_gives_one_line_and_writes_nothing(case, tmp_path, monkeypatch, capsys):
    check_case(case, tmp_path, monkeypatch, capsys)


@pytest.mark.parametrize("case", DIAGNOSE, ids=[getattr(c, "id", None) for c in DIAGNOSE])
def test_bad_diagnose_argument_gives_one_line_and_writes_nothing(case, tmp_path, monkeypatch, capsys):
    check_case(case, tmp_path, monkeypatch, capsys)


USAGE = [
    ["modes", "m.json", "--n", "abc"],
    ["frf", "m.json", "--fmax", "fast"],
    ["frf", "m.json", "--colour", "red"],
    ["lobes", "tip.h5", "--teeth", "2.5"],
    ["lobes"],
    ["modal-fit", "tip.uff", "--band", "10"],
    ["identify", "campaign.json"],
    ["predict"],
]


@pytest.mark.parametrize("args", USAGE, ids=["-".join(a) for a in USAGE])
def test_usage_error_exits_2_without_traceback_and_writes_nothing(args, tmp_path, monkeypatch, capsys):
    work = tmp_path / "work"
    work.mkdir()
    for name, content in _with_frf().items():
        p = work / name
        p.write_bytes(content) if isinstance(content, bytes) else p.write_text(content)
    copy_campaign(work)
    before = snapshot(work)
    code, _, err = run_main(args, work, monkeypatch, capsys)
    assert code == 2 and "Traceback" not in err, err
    assert err.startswith("error: "), err
    assert snapshot(work) == before


@pytest.mark.parametrize("args", USAGE, ids=["-".join(a) for a in USAGE])
def test_usage_error_is_one_line(args, tmp_path, monkeypatch, capsys):
    shutil.copy(MODEL_FIXTURE, tmp_path / "m.json")
    code, _, err = run_main(args, tmp_path, monkeypatch, capsys)
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("error: "), err
