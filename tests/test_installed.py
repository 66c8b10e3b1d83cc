"""When run by CI (`make test`), the suite must exercise the installed package, not the source tree."""

import os
from pathlib import Path

import pytest

import jointdb


@pytest.mark.skipif(os.environ.get("CI") != "true", reason="only meaningful on CI's non-editable install")
def test_jointdb_is_imported_from_the_installed_wheel():
    source_tree = Path(__file__).resolve().parents[1] / "jointdb"
    assert Path(jointdb.__file__).resolve().parent != source_tree, (
        "tests imported jointdb from the source tree; `make test` must test the installed package"
    )
