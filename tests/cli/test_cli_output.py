"""Output for people and scripts (issue 14): help text, plain untruncated tables and progress off a
terminal, `--out` files by suffix, `--version`, `-v/-q` logging, one `--plots DIR` option."""

from __future__ import annotations

import json
import logging
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from jointdb.cli._output import header, progress_line, write_rows
from jointdb.frf import FRF
from jointdb.io import write_frf_hdf5

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


def run(*args, **kw):
    """``python -m jointdb ARGS`` with stdout/stderr piped (not a terminal)."""
    return subprocess.run([sys.executable, "-m", "jointdb", *args], capture_output=True, text=True, env=ENV,
                          timeout=300, **kw)


@pytest.fixture(scope="module")
def tip_h5(tmp_path_factory):
    d = tmp_path_factory.mktemp("tip")
    f = np.linspace(100.0, 3000.0, 600)
    w, wn, z = 2 * np.pi * f, 2 * np.pi * 1500.0, 0.02
    h = 1.0 / (1e7 * (1 - (w / wn) ** 2 + 2j * z * w / wn))
    values = np.zeros((f.size, 2, 2), complex)
    values[:, 0, 0], values[:, 1, 1] = h, h
    write_frf_hdf5(d / "tip.h5", FRF(f, values, ["1x", "1y"], ["1x", "1y"]))
    return d / "tip.h5"


def _all_commands():
    import typer

    from jointdb.cli import app

    root = typer.main.get_command(app)
    out = []

    def walk(cmd, path):
        if hasattr(cmd, "commands"):
            for name, sub in cmd.commands.items():
                walk(sub, [*path, name])
        else:
            out.append((path, cmd))

    walk(root, [])
    return root, out


def test_help_shows_flags_as_flags_and_one_plot_option():
    root, commands = _all_commands()
    assert len(commands) > 20
    from jointdb.cli import app

    for path, cmd in commands:
        r = CliRunner().invoke(app, [*path, "--help"])
        assert r.exit_code == 0, (path, r.output)
        text = r.stdout
        assert "<bool>" not in text, path
        if "--json" in [o for p in cmd.params for o in getattr(p, "opts", [])]:
            assert any(line.split()[:1] == ["--json"] for line in text.splitlines()), path  # `--json  help`, no metavar
        assert "--plot " not in text and "--plot\n" not in text, path  # the deprecated spelling is hidden
    plotting = {" ".join(p) for p, c in commands if any("--plots" in getattr(q, "opts", []) for q in c.params)}
    assert {"frf", "identify", "couple", "predict", "modal-fit", "lobes", "diagnose"} <= plotting
    for path, cmd in commands:
        for p in cmd.params:
            if "--plots" in getattr(p, "opts", []):
                assert p.metavar == "DIR", path


def test_version_flag():
    import jointdb

    r = run("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"jointdb {jointdb.__version__}"


def test_headers_carry_units():
    assert header("depth_mm") == "depth [mm]"
    assert header("spindle_speed_rpm") == "spindle_speed [rpm]"
    assert header("k_x_n_per_m") == "k_x [N/m]"
    assert header("torque_nm") == "torque [N·m]"
    assert header("d_torque_nm") == "d_torque_nm"  # a dimensionless distance term, not a torque
    assert header("peak (Hz)") == "peak (Hz)"


def test_piped_table_is_plain_and_untruncated():
    long = "th-er32-carbide-" + "x" * 150
    code = ("from jointdb.cli._output import emit; "
            f"emit([{{'name': {long!r}, 'torque_nm': 40.0, 'materials': 'tungsten-carbide + steel'}}], title='t')")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env={**ENV, "COLUMNS": "80"})
    assert r.returncode == 0, r.stderr
    assert long in r.stdout and "tungsten-carbide + steel" in r.stdout and "…" not in r.stdout
    assert "torque [N·m]" in r.stdout
    assert not any(ch in r.stdout for ch in "┏┃│└")  # plain ASCII (Markdown) table, no box drawing
    assert "\x1b[" not in r.stdout  # no colour codes in a pipe
    code = "from jointdb.cli._output import emit; emit({'max |H[1x,1x]|': '4.5e-06 at 1888 Hz'})"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=ENV)
    row = next(x for x in r.stdout.splitlines() if "max" in x)
    assert row.replace("\\|", "").count("|") == 3  # a | inside a cell is escaped: still two columns


def test_piped_progress_prints_lines_with_counts_and_eta():
    code = ("import time\nfrom jointdb.cli._output import progress\n"
            "for _ in progress(range(4), description='cases', min_interval_s=0.0):\n    time.sleep(0.01)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=ENV)
    lines = [x for x in r.stderr.splitlines() if x.startswith("cases:")]
    assert [x.split()[1] for x in lines] == ["1/4", "2/4", "3/4", "4/4"]
    assert all("ETA" in x and "elapsed" in x for x in lines)
    assert progress_line("x", 5, 20, 10.0) == "x: 5/20 (25%), 10 s elapsed, ETA 30 s"


@pytest.mark.parametrize("suffix", [".csv", ".json", ".h5"])
def test_write_rows_round_trips(tmp_path, suffix):
    rows = [{"spindle_speed_rpm": 3000.0 + i, "depth_m": 1e-3 * (1 + i / 7), "kind": "hopf" if i % 2 else "flip",
             "lobe": i} for i in range(5)]
    path = write_rows(tmp_path / f"t{suffix}", rows, meta={"method": "milling-zoa"}, kind="lobes")
    if suffix == ".csv":
        import csv

        with path.open(newline="", encoding="utf-8") as fh:
            back = list(csv.DictReader(fh))
        got = [{k: (v if k == "kind" else float(v)) for k, v in r.items()} for r in back]
    elif suffix == ".json":
        doc = json.loads(path.read_text(encoding="utf-8"))
        assert doc["kind"] == "lobes" and doc["meta"] == {"method": "milling-zoa"}
        got = doc["rows"]
    else:
        with h5py.File(path, "r") as fh:
            g = fh["lobes"]
            assert json.loads(g.attrs["meta"]) == {"method": "milling-zoa"}
            cols = json.loads(g.attrs["columns"])
            data = {c: g[c][()] for c in cols}
        got = [{c: (data[c][i].decode() if isinstance(data[c][i], bytes) else float(data[c][i])) for c in cols}
               for i in range(5)]
    assert got == [{k: (float(v) if k != "kind" else v) for k, v in r.items()} for r in rows]  # exact (repr round-trip)


@pytest.mark.parametrize("suffix", [".csv", ".json", ".h5"])
def test_lobes_out_by_suffix_equals_json_rows(tmp_path, tip_h5, suffix):
    args = ["lobes", str(tip_h5), "--op", "milling", "--teeth", "2", "--kt", "6e8", "--kr", "2e8",
            "--rpm-min", "5000", "--rpm-max", "25000", "--n-speeds", "40"]
    r = run(*args, "--json")
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout)["rows"]
    out = tmp_path / f"lobes{suffix}"
    r = run(*args, "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert f"wrote {out} ({len(rows)} rows)" in r.stderr
    if suffix == ".json":
        back = json.loads(out.read_text(encoding="utf-8"))["rows"]
        assert back == rows
    elif suffix == ".h5":
        with h5py.File(out, "r") as fh:
            depth = fh["lobes"]["depth_m"][()]
        assert np.array_equal(depth, [x["depth_m"] for x in rows])
    else:
        import csv

        with out.open(newline="", encoding="utf-8") as fh:
            back = list(csv.DictReader(fh))
        assert [float(x["depth_m"]) for x in back] == [x["depth_m"] for x in rows]
    # the default output is a summary; depth in mm with the unit in the header
    r = run(*args)
    assert r.returncode == 0 and len(r.stdout.splitlines()) < 25 and "min_depth [mm]" in r.stdout
    floor_mm = min(x["depth_m"] for x in rows if x["kind"] != "fold") * 1e3
    line = next(x for x in r.stdout.splitlines() if "min_depth [mm]" in x)
    assert float(line.split("|")[2]) == pytest.approx(floor_mm, rel=1e-5)  # 6 significant digits shown


def test_lobes_plots_dir_and_deprecated_plot_file(tmp_path, tip_h5):
    args = ["lobes", str(tip_h5), "--op", "turning", "--kf", "1e9", "--n-speeds", "30"]
    r = run(*args, "--plots", str(tmp_path / "figs"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "figs" / "lobes.png").stat().st_size > 5000
    r = run(*args, "--plot", str(tmp_path / "old.png"))
    assert r.returncode == 0 and (tmp_path / "old.png").exists() and "deprecated" in r.stderr
    r = run(*args, "--plots", str(tmp_path / "no" / "such" / "dir"))
    assert r.returncode != 0 and r.stderr.startswith("error: --plots") and "Traceback" not in r.stderr


def test_verbose_and_quiet_set_the_logging_level(tip_h5, tmp_path):
    args = ["lobes", str(tip_h5), "--op", "turning", "--kf", "1e9", "--n-speeds", "30", "--out",
            str(tmp_path / "l.csv")]
    plain = run(*args)
    verbose = run("-v", *args)
    debug = run("-vv", *args)
    quiet = run("-q", *args)
    for r in (plain, verbose, debug, quiet):
        assert r.returncode == 0, r.stderr
    assert "INFO" not in plain.stderr and "wrote" in plain.stderr
    assert "INFO jointdb.stability._adaptive: lobes: 30 base speeds" in verbose.stderr
    assert "DEBUG jointdb.stability._adaptive: lobe refinement round 1" in debug.stderr
    assert quiet.stderr == ""  # only warnings and errors under -q
    assert quiet.stdout == plain.stdout  # results are not affected
    after = run(*args, "-q")  # the global flags may follow the command as well
    assert after.returncode == 0 and after.stderr == "" and after.stdout == plain.stdout


def test_configure_logging_levels():
    from jointdb.cli._output import configure_logging

    logger = logging.getLogger("jointdb")
    try:
        for (v, q), level in {(0, False): logging.WARNING, (1, False): logging.INFO, (2, False): logging.DEBUG,
                              (0, True): logging.ERROR}.items():
            configure_logging(v, q)
            assert logger.level == level
        assert sum(type(h).__name__ == "_StderrHandler" for h in logger.handlers) == 1  # not one per call
    finally:
        configure_logging(0, False)


def test_library_code_does_not_print():
    """Library modules log (logging.getLogger(__name__)); only the CLI and _output write to the streams."""
    import pathlib
    import re

    root = pathlib.Path(__file__).resolve().parents[2] / "jointdb"
    bad = []
    for p in root.rglob("*.py"):
        rel = p.relative_to(root).as_posix()
        if rel.startswith(("cli/", "migrations/")) or rel == "_output.py" or rel.endswith("__main__.py"):
            continue
        for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("#")[0]
            if re.search(r"(^|[^.\w])print\(|sys\.std(out|err)\.write", code) and ">>>" not in line:
                bad.append(f"{rel}:{n}")
    assert not bad, bad
