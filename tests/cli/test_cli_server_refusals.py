"""Commands that need the database itself say so over --server (issue 21, item 4) instead of
quietly using a local database."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("args", [["db", "info"], ["tokens", "list"], ["worker"], ["joints", "export", "x.h5"],
                                  ["joints", "import", "x.h5"]])
def test_local_only_commands_refuse_server(args, tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("JOINTDB_URL", "JOINTDB_SERVER")}
    out = subprocess.run([sys.executable, "-m", "jointdb", "--server", "http://127.0.0.1:9", *args],
                         capture_output=True, text=True, cwd=tmp_path, env={**env, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 2, out.stderr
    assert "does not work over --server" in out.stderr and "--db" in out.stderr
    assert not any(tmp_path.iterdir())  # nothing made locally
