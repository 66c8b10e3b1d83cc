"""The bundled catalogue (joints and parts), identified and catalogued once per module as `jointdb demo` does."""

import pytest

from jointdb.store import Repository
from jointdb.usecases._demo import run_main_job


@pytest.fixture(scope="module")
def catalogue(tmp_path_factory):
    """``(repo, sqlite path)`` of the bundled catalogue after the main job."""
    tmp = tmp_path_factory.mktemp("cat")
    run_main_job(tmp / "out", f"sqlite:///{tmp / 'joints.sqlite'}", say=lambda _: None, n_speeds=40)
    repo = Repository(f"sqlite:///{tmp / 'joints.sqlite'}")
    yield repo, tmp / "joints.sqlite"
    repo.close()

