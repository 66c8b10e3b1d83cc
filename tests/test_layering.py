"""The numerical core must not pull in I/O or UI libraries (README, "Layout")."""

import subprocess
import sys

import pytest

CORE = [
    "jointdb",
    "jointdb.frf",
    "jointdb.fe",
    "jointdb.coupling",
    "jointdb.modal",
    "jointdb.stack",
    "jointdb.stability",
    "jointdb.diagnose",
]
HEAVY = ["sqlalchemy", "h5py", "typer", "matplotlib", "fastapi", "pyuff"]


@pytest.mark.parametrize("module", CORE)
def test_core_module_imports_no_io_or_ui_library(module):
    code = (
        "import importlib, sys\n"
        f"importlib.import_module({module!r})\n"
        f"print(','.join(h for h in {HEAVY!r} if h in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"{module} imports {out.stdout.strip()}"


def test_cli_help_runs():
    out = subprocess.run([sys.executable, "-m", "jointdb", "--help"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "Usage" in out.stdout


def test_usage_error_exits_2_without_traceback():
    out = subprocess.run([sys.executable, "-m", "jointdb", "modes", "--no-such-option"], capture_output=True, text=True)
    assert out.returncode == 2
    assert "Traceback" not in out.stderr
    assert "No such option" in out.stderr
