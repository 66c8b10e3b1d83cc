from pathlib import Path

import pytest

from jointdb.store import Repository
from jointdb.usecases import catalogue_bundled_parts, catalogue_campaign

BUNDLED = Path(__file__).resolve().parents[2] / "fixtures" / "bundled" / "catalogue"


@pytest.fixture(scope="module")
def catalogue(tmp_path_factory):
    """``(repo, sqlite path)`` of the bundled catalogue: its campaigns identified and catalogued and its
    parts added, as the main job's first step does (the rest of the main job — prediction, lobes,
    plots — is not needed here and is tested in tests/test_journey.py)."""
    tmp = tmp_path_factory.mktemp("cat")
    repo = Repository(f"sqlite:///{tmp / 'joints.sqlite'}")
    for path in sorted((BUNDLED / "campaigns").glob("*/campaign.json")):
        catalogue_campaign(repo, path)
    catalogue_bundled_parts(repo, BUNDLED)
    yield repo, tmp / "joints.sqlite"
    repo.close()
