"""Shared pieces of the fuzz corpus: valid seed files, a case record and the CLI runner.

Every case writes its files into a fresh directory, runs the real entry point
(``jointdb.cli.main``, the console script's function) in-process with that
directory as the working directory, and checks what a user would see: the
exit code, exactly one line on stderr and no traceback, and a directory left
exactly as it was (nothing written, nothing half-written).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from jointdb.cli import main
from jointdb.frf import FRF

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"
MODEL_FIXTURE = FIXTURES / "models" / "end-mill-in-holder.json"
STACK_FIXTURE = FIXTURES / "stacks" / "endmill-modelled-spindle.json"
CAMPAIGN_FIXTURE = FIXTURES / "campaigns" / "th-steel-30nm"

#: Warning classes Python does not show to a console user by default.
_HIDDEN_BY_DEFAULT = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)

#: Exit codes of jointdb.errors (InputError, NotFoundError, ...).
INPUT, NOT_FOUND, INTEGRITY = 2, 3, 5


@dataclass
class Case:
    """One malformed input: the files to create, the command line, the expected exit code(s).

    ``files`` maps a relative path to bytes, text, or a callable ``f(path)`` that
    writes it. ``codes`` lists the documented exit codes that are acceptable
    (usually exactly one). ``match`` is a fragment the one-line message must
    contain (case-insensitive), e.g. the field name or the file name.
    """

    id: str
    args: list[str]
    files: dict[str, object] = field(default_factory=dict)
    codes: tuple[int, ...] = (INPUT,)
    match: str | None = None


def small_frf(n: int = 16, outputs=("1x",), inputs=("1x",)) -> FRF:
    """A small receptance on 10..(10+5n) Hz, deterministic values."""
    freq = 10.0 + 5.0 * np.arange(n)
    rng = np.random.default_rng(1)
    shape = (n, len(outputs), len(inputs))
    values = (rng.normal(size=shape) + 1j * rng.normal(size=shape)) * 1e-6
    return FRF(freq, values, outputs, inputs, "receptance")


def seed_bytes(kind: str) -> bytes:
    """Bytes of a valid seed file: ``uff`` (ASCII 58), ``uffb`` (58b), ``h5``, ``csv``."""
    cache = _SEEDS.get(kind)
    if cache is not None:
        return cache
    import tempfile

    from jointdb.io import write_frf_csv, write_frf_hdf5, write_uff58

    frf = small_frf()
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / f"seed.{ {'uff': 'uff', 'uffb': 'uff', 'h5': 'h5', 'csv': 'csv'}[kind]}"
        if kind == "uff":
            write_uff58(p, frf)
        elif kind == "uffb":
            write_uff58(p, frf, binary=True)
        elif kind == "h5":
            write_frf_hdf5(p, frf, {"test": 1})
        else:
            write_frf_csv(p, frf)
        data = p.read_bytes()
    _SEEDS[kind] = data
    return data


_SEEDS: dict[str, bytes] = {}


def model_doc() -> dict:
    return json.loads(MODEL_FIXTURE.read_text())


def stack_doc() -> dict:
    return json.loads(STACK_FIXTURE.read_text())


def campaign_doc() -> dict:
    return json.loads((CAMPAIGN_FIXTURE / "campaign.json").read_text())


def edited(doc_factory: Callable[[], dict], change: Callable[[dict], object]) -> str:
    doc = doc_factory()
    change(doc)
    return json.dumps(doc)


def snapshot(directory: Path) -> dict[str, str]:
    """Relative path -> sha256 (or "<dir>") of everything under ``directory``."""
    out = {}
    for p in sorted(directory.rglob("*")):
        rel = str(p.relative_to(directory))
        out[rel] = "<dir>" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def materialise(case: Case, directory: Path) -> None:
    for rel, content in case.files.items():
        p = directory / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        if callable(content):
            content(p)
        elif isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(str(content), encoding="utf-8")


def copy_campaign(directory: Path) -> None:
    for f in CAMPAIGN_FIXTURE.iterdir():
        shutil.copy(f, directory / f.name)


def run_main(args: list[str], cwd: Path, monkeypatch, capsys) -> tuple[int, str, str]:
    """Run ``jointdb ARGS`` through the console-script function in ``cwd``; (exit code, stdout, stderr)."""
    monkeypatch.chdir(cwd)
    monkeypatch.setattr(sys, "argv", ["jointdb", *map(str, args)])
    # never touch a real database: an explicit, absent SQLite file
    monkeypatch.setenv("JOINTDB_URL", str(cwd.parent / "no-such-db.sqlite"))
    monkeypatch.setenv("COLUMNS", "200")
    capsys.readouterr()
    code = 0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            main()
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    out = capsys.readouterr()
    # a console user would see every warning on stderr too (two lines each: message and source line)
    shown = "".join(f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}\n  (source line)\n"
                    for w in caught if not issubclass(w.category, _HIDDEN_BY_DEFAULT))
    return code, out.out, out.err + shown


def check_case(case: Case, tmp_path: Path, monkeypatch, capsys) -> str:
    """Run one case and assert the contract; returns the error line."""
    work = tmp_path / "work"
    work.mkdir()
    if case.files.get("__campaign__") is not None:
        copy_campaign(work)
    materialise(Case(case.id, case.args, {k: v for k, v in case.files.items() if k != "__campaign__"}), work)
    before = snapshot(work)
    code, out, err = run_main(case.args, work, monkeypatch, capsys)
    lines = err.splitlines()
    assert "Traceback" not in err, err
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}:\n{err}"
    assert lines[0].startswith("error: "), lines[0]
    assert code in case.codes, f"exit {code} (expected {case.codes}): {lines[0]}"
    if case.match is not None:
        assert case.match.lower() in lines[0].lower(), f"{case.match!r} not in {lines[0]!r}"
    assert snapshot(work) == before, "the command changed the directory"
    assert not os.path.exists(tmp_path / "no-such-db.sqlite"), "a database was created"
    return lines[0]
