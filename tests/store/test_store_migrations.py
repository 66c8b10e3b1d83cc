"""Alembic migrations: from empty, down, up again with data preserved; models == migrations."""

from __future__ import annotations

import subprocess
import sys

import pytest
import sqlalchemy as sa
from store_helpers import planar_conditions, spring_joint

from jointdb.errors import InputError
from jointdb.store import current_revision, downgrade, head_revision, upgrade

#: these tests are about creating and migrating databases: no copy of a migrated template (tests/sqlite_template.py)
pytestmark = pytest.mark.real_migrations


def _tables(url):
    engine = sa.create_engine(url)
    try:
        return set(sa.inspect(engine).get_table_names())
    finally:
        engine.dispose()


def test_upgrade_from_empty_down_and_up_with_data_preserved(empty_backend):
    url = empty_backend.url
    assert current_revision(url) is None
    assert upgrade(url) == head_revision()
    assert {"joints", "joint_versions", "labels", "joint_states", "audit_log"} <= _tables(url)
    repo = empty_backend.repo()
    jv = repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    repo.label("T1", 1, "released")
    repo.close()

    assert downgrade(url, "0001") == "0001"  # triggers, query index and tokens gone, tables and data kept
    with sa.create_engine(url).connect() as conn:
        assert conn.execute(sa.text("SELECT count(*) FROM joint_versions")).scalar_one() == 1
    with pytest.raises(InputError, match="jointdb db upgrade"):
        empty_backend.repo()  # outdated schema is refused with advice, never used silently
    assert upgrade(url) == head_revision()
    repo = empty_backend.repo()
    again = repo.get("T1", label="released")
    assert again.record_sha256 == jv.record_sha256
    assert repo.load_frf(again).allclose(spring_joint(), rtol=0)
    assert repo.check().ok
    with pytest.raises(sa.exc.DBAPIError, match="immutable"):  # triggers are back
        with repo.write_engine.begin() as conn:
            conn.exec_driver_sql("DELETE FROM joint_versions")
    repo.close()

    assert downgrade(url, "base") is None
    assert not ({"joints", "joint_versions"} & _tables(url))
    assert upgrade(url) == head_revision()


def test_models_match_migrations(backend):
    from alembic.autogenerate import compare_metadata
    from alembic.runtime.migration import MigrationContext

    from jointdb.store._models import Base

    engine = sa.create_engine(backend.url)
    try:
        with engine.connect() as conn:
            diff = compare_metadata(MigrationContext.configure(conn, opts={"compare_type": True}), Base.metadata)
    finally:
        engine.dispose()
    assert diff == []


def test_new_sqlite_database_is_created_on_first_use(tmp_path):
    from jointdb.store import Repository

    repo = Repository(tmp_path / "sub" / "new.sqlite")
    assert current_revision(repo.url) == head_revision()
    assert repo.blobs.root == tmp_path / "sub" / "new.sqlite.blobs"
    with repo.read_engine.connect() as conn:
        assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
        assert conn.exec_driver_sql("PRAGMA foreign_keys").scalar() == 1
        assert conn.exec_driver_sql("PRAGMA busy_timeout").scalar() >= 1000


def test_postgres_is_not_created_silently(empty_backend):
    if empty_backend.name != "postgresql":
        pytest.skip("auto-creation is the SQLite default")
    with pytest.raises(InputError, match="jointdb db upgrade"):
        empty_backend.repo()


def test_migrations_run_without_alembic_ini(tmp_path):
    """The runtime builds its Alembic config from the package path (wheel installs)."""
    code = (
        "from jointdb.store import upgrade, head_revision;"
        f"assert upgrade({str(tmp_path / 'x.sqlite')!r}) == head_revision(); print('ok')"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_location_defaults(tmp_path, monkeypatch):
    from jointdb.store._db import blob_dir, resolve_url

    monkeypatch.delenv("JOINTDB_URL", raising=False)
    monkeypatch.delenv("JOINTDB_BLOBS", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    url = resolve_url(None)
    assert url == f"sqlite:///{tmp_path}/jointdb/jointdb.sqlite"
    assert blob_dir(url) == tmp_path / "jointdb" / "jointdb.sqlite.blobs"
    monkeypatch.setenv("JOINTDB_URL", "postgresql+psycopg://u@h/db")
    assert resolve_url(None) == "postgresql+psycopg://u@h/db"
    with pytest.raises(InputError, match="JOINTDB_BLOBS"):
        blob_dir(resolve_url(None))
    monkeypatch.setenv("JOINTDB_BLOBS", str(tmp_path / "shared"))
    assert blob_dir(resolve_url(None)) == tmp_path / "shared"
    with pytest.raises(InputError, match="unsupported database"):
        resolve_url("mysql://x/y")
