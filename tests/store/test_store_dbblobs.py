"""Blobs kept in the database (``blobs="database"``): same guarantees as the file store —
content-addressed, idempotent, verified on every read, gc never removes a referenced blob."""

from __future__ import annotations

import pytest
import sqlalchemy as sa
from store_helpers import planar_conditions, spring_joint

from jointdb.errors import IntegrityError, NotFoundError


@pytest.fixture
def dbrepo(backend):
    from jointdb.store import Repository

    r = Repository(backend.url, blobs="database")
    yield r
    r.close()


def _raw(repo, sql: str, **params):
    with repo.write_engine.begin() as conn:
        return conn.execute(sa.text(sql), params)


def test_catalogue_and_load_from_database_blobs(dbrepo, backend):
    frf = spring_joint()
    jv = dbrepo.catalogue("DB-1", "tool-holder", frf, planar_conditions(), "spring-damper-planar")
    assert dbrepo.load_frf(jv).allclose(frf, rtol=0)
    assert not backend.blobs.exists()  # nothing on the file system
    assert dbrepo.blobs.put(frf) == jv.blob_sha256  # idempotent
    with dbrepo.write_engine.connect() as conn:
        assert conn.execute(sa.text("select count(*) from frf_blobs")).scalar() == 1
    assert dbrepo.check().ok
    assert "frf_blobs" in dbrepo.blobs.root


@pytest.mark.parametrize("where", [600, 20, -5])  # user block, HDF5 metadata / chunk, last byte
def test_every_read_verifies(dbrepo, where):
    jv = dbrepo.catalogue("DB-2", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    with dbrepo.write_engine.connect() as conn:
        data = bytearray(conn.execute(sa.text("select data from frf_blobs")).scalar())
    data[where] ^= 0x01
    _raw(dbrepo, "update frf_blobs set data = :d", d=bytes(data))
    with pytest.raises(IntegrityError, match="corrupt"):
        dbrepo.load_frf(jv)
    report = dbrepo.check()
    assert not report.ok and "corrupt" in report.problems[0]
    assert dbrepo.blobs.put(spring_joint()) == jv.blob_sha256  # a put repairs the corrupt copy
    assert dbrepo.load_frf(jv).allclose(spring_joint(), rtol=0) and dbrepo.check().ok


def test_missing_blob_is_not_found(dbrepo):
    jv = dbrepo.catalogue("DB-3", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    dbrepo.blobs.remove(jv.blob_sha256)
    with pytest.raises(NotFoundError):
        dbrepo.load_frf(jv)
    assert not dbrepo.check().ok
    with pytest.raises(IntegrityError):
        dbrepo.blobs.get("../../etc/passwd")


def test_gc_removes_only_old_unreferenced_blobs(dbrepo):
    kept = dbrepo.catalogue("DB-4", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    orphan = dbrepo.blobs.put(spring_joint(k=(3e6, 9e4)))
    young = dbrepo.blobs.put(spring_joint(k=(4e6, 9e4)))
    _raw(dbrepo, "update frf_blobs set touched_at = :t where sha256 != :y",
         t=__import__("datetime").datetime(2000, 1, 1), y=young)
    assert set(dbrepo.gc(min_age_s=3600, dry_run=True)) == {orphan}
    assert dbrepo.gc(min_age_s=3600) == [orphan]
    assert dbrepo.blobs.exists(kept.blob_sha256) and dbrepo.blobs.exists(young)
    assert not dbrepo.blobs.exists(orphan) and dbrepo.check().ok
    # a put of an old blob refreshes it: the next gc spares it
    again = dbrepo.blobs.put(spring_joint(k=(3e6, 9e4)))
    assert dbrepo.gc(min_age_s=3600) == [] and dbrepo.blobs.exists(again)


def test_blob_and_version_commit_in_one_transaction(dbrepo, monkeypatch):
    """A version whose row fails to write leaves no blob behind (issue 26, item 5): the blob is
    inserted in the version's own transaction, not committed before it."""
    import jointdb.store._repository as repository_module

    def failing_write(session, **kwargs):
        session.flush()  # the blob row is in this transaction already
        raise RuntimeError("the row write failed")

    monkeypatch.setattr(repository_module, "write_version", failing_write)
    with pytest.raises(RuntimeError, match="row write failed"):
        dbrepo.catalogue("DB-TX", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    with dbrepo.write_engine.connect() as conn:
        assert conn.execute(sa.text("select count(*) from frf_blobs")).scalar() == 0
    monkeypatch.undo()
    jv = dbrepo.catalogue("DB-TX", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    assert dbrepo.load_frf(jv).allclose(spring_joint(), rtol=0) and dbrepo.check().ok


def _count(repo, table: str) -> int:
    with repo.write_engine.connect() as conn:
        return conn.execute(sa.text(f"select count(*) from {table}")).scalar()


def test_blob_bytes_that_do_not_read_back_write_nothing(dbrepo, monkeypatch):
    """The bytes are decoded (on a worker, while the transaction runs) and compared with the FRF
    before they are inserted: bytes with a flipped byte in a data chunk are refused, with no blob
    and no version row."""
    import jointdb.store._dbblobs as dbblobs_mod
    from test_store_blobs import flip_in_values_chunk

    real = dbblobs_mod.blob_bytes
    monkeypatch.setattr(dbblobs_mod, "blob_bytes", lambda frf, digest=None: (
        digest, flip_in_values_chunk(real(frf, digest)[1])))
    with pytest.raises(IntegrityError, match="did not read back"):
        dbrepo.catalogue("DB-BAD", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    assert _count(dbrepo, "frf_blobs") == 0 and _count(dbrepo, "joint_versions") == 0
    monkeypatch.undo()
    jv = dbrepo.catalogue("DB-BAD", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    assert dbrepo.load_frf(jv).allclose(spring_joint(), rtol=0) and dbrepo.check().ok


def test_a_refused_version_writes_no_blob(dbrepo):
    """No conflict check runs before the transaction with database blobs: the refusal inside it
    (a contradicting torque, the joint's type) rolls the new blob back with it."""
    from jointdb.errors import ConflictError

    dbrepo.catalogue("DB-R", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    cond = planar_conditions(torque=999.0)
    with pytest.raises(ConflictError, match="not the same joint"):
        dbrepo.catalogue("DB-R", "tool-holder", spring_joint(k=(7e6, 9e4)), cond, "spring-damper-planar")
    with pytest.raises(ConflictError, match="is a tool-holder joint"):
        dbrepo.catalogue("DB-R", "holder-spindle", spring_joint(k=(8e6, 9e4)), planar_conditions(),
                         "spring-damper-planar")
    assert _count(dbrepo, "frf_blobs") == 1 and _count(dbrepo, "joint_versions") == 1
    # the raw measurements' blobs too are written in the refused version's transaction, not before it
    raw = {"g11": spring_joint(k=(3e6, 5e4)), "g22": spring_joint(k=(4e6, 6e4))}
    with pytest.raises(ConflictError, match="is a tool-holder joint"):
        dbrepo.catalogue("DB-R", "holder-spindle", spring_joint(k=(8e6, 9e4)), planar_conditions(),
                         "spring-damper-planar", raw_frfs=raw)
    assert _count(dbrepo, "frf_blobs") == 1
    with_raw = dbrepo.catalogue("DB-W", "tool-holder", spring_joint(k=(5e6, 9e4)), planar_conditions(),
                                "spring-damper-planar", raw_frfs=raw)
    assert _count(dbrepo, "frf_blobs") == 4 and set(with_raw.raw_blobs) == {"g11", "g22"}
    assert dbrepo.load_frf(with_raw).allclose(spring_joint(k=(5e6, 9e4)), rtol=0)
    forced = dbrepo.catalogue("DB-R", "tool-holder", spring_joint(k=(7e6, 9e4)), cond, "spring-damper-planar",
                              force=True)
    assert forced.version == 2 and _count(dbrepo, "frf_blobs") == 5 and dbrepo.check().ok


def test_a_postgresql_version_is_five_round_trips(dbrepo, backend, monkeypatch):
    """On PostgreSQL a new version of a joint is BEGIN, three batches of statements (one round trip each:
    the lock and head; the rows, index, stamp and chain head; the chain entries and the blob) and COMMIT
    (jointdb/store/_catalogue.py). Counted at psycopg: every statement or command it waits for outside
    a pipeline, and every pipeline sync; the rows and the chain are checked afterwards."""
    if backend.name != "postgresql":
        pytest.skip("round trips of the PostgreSQL catalogue")
    import psycopg._cursor_base as cursor_base
    import psycopg._pipeline_base as pipeline_base
    import psycopg.generators as generators

    trips = []
    for module, name in ((cursor_base, "execute"), (generators, "execute"), (pipeline_base.BasePipeline, "_sync_gen"),
                         (pipeline_base.BasePipeline, "_exit_gen")):
        real = getattr(module, name)
        monkeypatch.setattr(module, name, lambda *a, _real=real, _name=name, **k: trips.append(_name) or _real(*a, **k))
    dbrepo.catalogue("RT", "tool-holder", spring_joint(k=(1e6, 1e4)), planar_conditions(), "spring-damper-planar")
    for n in range(3):
        trips.clear()
        dbrepo.catalogue("RT", "tool-holder", spring_joint(k=(2e6 + n, 1e4)), planar_conditions(),
                         "spring-damper-planar", force=True)
        assert len(trips) <= 5, trips
    monkeypatch.undo()
    assert [v.version for v in dbrepo.history("RT")] == [1, 2, 3, 4] and dbrepo.check().ok


def test_a_statement_refused_inside_a_batch_rolls_back_everything(dbrepo, monkeypatch):
    """A statement the server refuses in the middle of the version's statements (here a CHECK constraint
    of the version row; on PostgreSQL inside a batch sent in one round trip) fails the catalogue with the
    server's message, writes nothing (no version, no index row, no blob, no chain entry), and the
    connection goes on working."""
    from jointdb.errors import JointdbError
    from jointdb.store import _catalogue

    dbrepo.catalogue("BATCH", "tool-holder", spring_joint(k=(1e6, 1e4)), planar_conditions(), "spring-damper-planar")
    counts = {t: _count(dbrepo, t) for t in ("joint_versions", "query_versions", "frf_blobs", "history_chain")}
    real = _catalogue._version_row

    def negative_preload(*args):
        row = real(*args)
        row.preload_n = -1.0  # the table's CHECK (preload_n >= 0) refuses it
        return row

    monkeypatch.setattr(_catalogue, "_version_row", negative_preload)
    with pytest.raises(JointdbError, match="preload_nonneg"):
        dbrepo.catalogue("BATCH", "tool-holder", spring_joint(k=(2e6, 1e4)), planar_conditions(),
                         "spring-damper-planar", force=True)
    monkeypatch.undo()
    assert {t: _count(dbrepo, t) for t in counts} == counts
    jv = dbrepo.catalogue("BATCH", "tool-holder", spring_joint(k=(3e6, 1e4)), planar_conditions(),
                          "spring-damper-planar", force=True)
    assert jv.version == 2 and dbrepo.load_frf(jv).allclose(spring_joint(k=(3e6, 1e4)), rtol=0)
    assert dbrepo.check().ok
