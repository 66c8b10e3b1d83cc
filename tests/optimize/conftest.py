import shutil
from pathlib import Path

import pytest

from jointdb.store import Repository
from jointdb.usecases import catalogue_bundled_parts, catalogue_campaign

BUNDLED = Path(__file__).resolve().parents[2] / "fixtures" / "bundled" / "catalogue"


@pytest.fixture(scope="session")
def _bundled_catalogue_files(tmp_path_factory):
    """A folder holding ``joints.sqlite`` (and its blob store) of the bundled catalogue, built once per test
    process: its campaigns identified and catalogued and its parts added, as the main job's first step does."""
    tmp = tmp_path_factory.mktemp("cat-master")
    repo = Repository(f"sqlite:///{tmp / 'joints.sqlite'}")
    try:
        for path in sorted((BUNDLED / "campaigns").glob("*/campaign.json")):
            catalogue_campaign(repo, path)
        catalogue_bundled_parts(repo, BUNDLED)
    finally:
        repo.close()
    return tmp


@pytest.fixture(scope="module")
def catalogue(_bundled_catalogue_files, tmp_path_factory):
    """``(repo, sqlite path)`` of the bundled catalogue: a module's own copy of the session's build (the
    database file and its blob store), so what one module writes no other sees (the rest of the main job —
    prediction, lobes, plots — is not needed here and is tested in tests/test_journey.py)."""
    tmp = tmp_path_factory.mktemp("cat")
    shutil.copytree(_bundled_catalogue_files, tmp, dirs_exist_ok=True)
    repo = Repository(f"sqlite:///{tmp / 'joints.sqlite'}")
    yield repo, tmp / "joints.sqlite"
    repo.close()
