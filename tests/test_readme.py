"""The README's examples run as written, in order, from a fresh clone (a doc test).

Every fenced block of language ``sh`` or ``python`` in README.md is a command
block. The blocks run one after the other in one temporary directory that holds
a copy of the clone's ``fixtures/`` and ``tests/data/`` (what a fresh clone has),
with ``jointdb`` on PATH (this interpreter's package) and a private HOME, so
nothing reaches the user's files or the per-user database. Shell blocks run in
bash with ``set -e`` (``pipefail`` too); variables they export carry over to the
next block, as in one terminal session. A Python block runs as a script.

Convention for a block that cannot run here: the line(s) right before its
fence hold ``<!-- doctest: skip — reason -->``. Each such block is reported as a
skipped test with its README line and reason. A command in an indented code
block (not fenced) is refused, so no example escapes the test.

Besides exit codes, the test checks that no block changes a file an earlier
block wrote (databases and their blob stores excepted: they grow by design).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
RUN_LANGS = {"sh", "bash", "python"}
SKIP = re.compile(r"<!--\s*doctest:\s*skip\s*[—:-]+\s*(.+?)\s*-->")
FENCE = re.compile(r"^```\s*([A-Za-z0-9_+-]*)\s*$")
#: budget for the whole README (the suite runs on 2 cores); a block taking longer than this fails
TIMEOUT_S = 600


@dataclass(frozen=True)
class Block:
    line: int  # README line of the opening fence (1-based)
    lang: str
    text: str
    skip: str | None


def parse_readme(text: str) -> list[Block]:
    """Fenced blocks with their language, README line and skip reason (None: run it)."""
    lines = text.splitlines()
    blocks: list[Block] = []
    k = 0
    while k < len(lines):
        m = FENCE.match(lines[k])
        if not m:
            k += 1
            continue
        start, lang = k, m.group(1).lower()
        k += 1
        body = []
        while k < len(lines) and not lines[k].startswith("```"):
            body.append(lines[k])
            k += 1
        if k == len(lines):
            raise AssertionError(f"README.md line {start + 1}: code fence never closed")
        k += 1
        reason = None
        j = start - 1
        while j >= 0 and lines[j].strip() == "":
            j -= 1
        if j >= 0:
            s = SKIP.search(lines[j])
            if s:
                reason = s.group(1)
        blocks.append(Block(start + 1, lang, "\n".join(body) + "\n", reason))
    return blocks


def unfenced_commands(text: str) -> list[int]:
    """README lines of indented (4-space) code that starts with a `jointdb` command."""
    out, in_fence = [], False
    for n, line in enumerate(text.splitlines(), start=1):
        if line.startswith("```"):
            in_fence = not in_fence
        elif not in_fence and re.match(r"^ {4,}(\$ )?jointdb\s", line):
            out.append(n)
    return out


def _blocks() -> list[Block]:
    if not README.is_file():
        return []
    return parse_readme(README.read_text(encoding="utf-8"))


BLOCKS = _blocks()


def test_parser_finds_blocks_and_skip_markers():
    text = "x\n<!-- doctest: skip — needs a server -->\n```sh\njointdb db upgrade\n```\n\n```python\nprint(1)\n```\n"
    got = parse_readme(text)
    assert [(b.line, b.lang, b.skip) for b in got] == [(3, "sh", "needs a server"), (7, "python", None)]
    assert unfenced_commands("text\n    jointdb demo\n```sh\n    jointdb x\n```\n") == [2]


@pytest.mark.skipif(not README.is_file(), reason="README.md not next to the tests (installed copy)")
def test_every_readme_command_is_in_a_fenced_block():
    lines = unfenced_commands(README.read_text(encoding="utf-8"))
    assert not lines, f"README.md lines {lines}: commands in indented blocks are not run by the doc test; fence them"


@pytest.mark.parametrize("block", [b for b in BLOCKS if b.skip], ids=lambda b: f"line{b.line}")
def test_skipped_readme_block(block):
    pytest.skip(f"README.md line {block.line}: {block.skip}")


def _snapshot(root: Path) -> dict[str, tuple[int, int]]:
    snap = {}
    for p in root.rglob("*"):
        if p.is_file() and not p.is_symlink():
            st = p.stat()
            snap[p.relative_to(root).as_posix()] = (st.st_size, st.st_mtime_ns)
    return snap


def _grows_by_design(rel: str) -> bool:
    """Database files and the blob stores beside them change as the database is used."""
    parts = rel.split("/")
    return any(".sqlite" in part for part in parts) or "blobs" in parts


@pytest.mark.skipif(not README.is_file(), reason="README.md not next to the tests (installed copy)")
def test_readme_blocks_run_in_order(tmp_path):
    runnable = [b for b in BLOCKS if b.skip is None and b.lang in RUN_LANGS]
    assert len(runnable) >= 10, "the README lost its examples"
    work = tmp_path / "clone"
    work.mkdir()
    shutil.copytree(REPO / "fixtures", work / "fixtures", symlinks=False,
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(REPO / "tests" / "data", work / "tests" / "data")
    bindir = tmp_path / "bin"
    bindir.mkdir()
    (bindir / "jointdb").write_text(f'#!/bin/sh\nexec "{sys.executable}" -m jointdb "$@"\n')
    (bindir / "jointdb").chmod(0o755)
    (bindir / "python").write_text(f'#!/bin/sh\nexec "{sys.executable}" "$@"\n')  # a symlink would lose a venv
    (bindir / "python").chmod(0o755)
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith("JOINTDB_")}
    env.update(HOME=str(home), PATH=f"{bindir}{os.pathsep}{env.get('PATH', '')}", MPLBACKEND="Agg",
               OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", COLUMNS="200")
    state = tmp_path / "session.env"  # variables exported by one block, seen by the next
    state.write_text("")
    timings = []
    before = _snapshot(work)
    for n, block in enumerate(runnable, start=1):
        where = f"README.md block {n} (line {block.line}, {block.lang})"
        if block.lang == "python":
            script = tmp_path / f"readme_block_{n}.py"
            script.write_text(block.text)
            cmd = f'set -eo pipefail\nsource "{state}"\npython "{script}"\n'
        else:
            cmd = f'set -eo pipefail\nsource "{state}"\n{block.text}\nexport -p > "{state}"\n'
        t0 = time.perf_counter()
        r = subprocess.run(["bash", "-c", cmd], cwd=work, env=env, capture_output=True, text=True,
                           timeout=TIMEOUT_S)
        timings.append((block.line, time.perf_counter() - t0))
        print(f"{where}: {timings[-1][1]:.1f} s", file=sys.stderr, flush=True)
        assert r.returncode == 0, (
            f"{where} failed with exit code {r.returncode}:\n{block.text}\n--- stderr (tail) ---\n"
            + "\n".join(r.stderr.splitlines()[-15:])
        )
        after = _snapshot(work)
        changed = sorted(k for k, v in before.items() if k in after and after[k] != v and not _grows_by_design(k))
        removed = sorted(k for k in before if k not in after and not _grows_by_design(k))
        assert not changed and not removed, f"{where} overwrote {changed[:5]} / removed {removed[:5]}"
        before = after
    print("README block timings: " + ", ".join(f"line {ln}: {dt:.1f} s" for ln, dt in timings))
