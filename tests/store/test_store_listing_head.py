"""The listing's maintained head (``query_versions.listed``, ``name``) and counts (``query_counts``):
after any sequence of catalogue / deprecate / undeprecate / label writes they equal what history
says (the rows recomputed from scratch by ``index_problems``, and ``Repository.get`` per joint),
the totals of unfiltered and filtered listings match a count of that reference, a migration from
``0009`` fills them for existing data, and a page reads O(page) index rows (query plan)."""

from __future__ import annotations

import numpy as np
import pytest
import sqlalchemy as sa
from store_helpers import planar_conditions, spring_joint

from jointdb.store import downgrade, upgrade
from jointdb.store._index import index_problems

KIND = "spring-damper-planar"


def _reference(repo, names) -> dict[str, tuple[int, str]]:
    """``{name: (version, state)}`` of what ``get`` returns for each joint (the listing's definition)."""
    out = {}
    for name in sorted(names):
        v = repo.get(name)
        out[name] = (v.version, v.state)
    return out


def _check(repo, names, types) -> None:
    with repo.read_engine.connect() as conn:
        assert index_problems(conn) == []
    ref = _reference(repo, names)
    page = repo.list_page(limit=None)
    assert {v.name: (v.version, v.state) for v in page.items} == ref and page.total == len(ref)
    active = {n for n, (_, s) in ref.items() if s == "active"}
    only_active = repo.list_page(include_deprecated=False, limit=3)
    assert only_active.total == len(active)
    deprecated = repo.list_page(state="deprecated", limit=2)
    assert deprecated.total == len(ref) - len(active)
    for t in ("tool-holder", "holder-spindle"):
        typed = repo.list_page(t, limit=2)
        assert typed.total == sum(types[n] == t for n in ref)
    listed = [v.name for v in page.items]
    assert listed == sorted(listed)


def test_head_and_counts_follow_every_write(repo):
    rng = np.random.default_rng(23)
    names, types, k, seen = set(), {}, 1e6, set()
    for step in range(40):
        op = int(rng.integers(6)) if names else 0
        seen.add(op)
        name = f"H{int(rng.integers(6))}" if op == 0 else sorted(names)[int(rng.integers(len(names)))]
        if op in (0, 1):  # a new version (a new joint on op 0 when the name is new)
            k *= 1.1
            jtype = types.get(name) or ("tool-holder" if len(types) % 2 == 0 else "holder-spindle")
            repo.catalogue(name, jtype, spring_joint(k=(k, 8e4)), planar_conditions(), KIND)
            names.add(name)
            types[name] = jtype
        elif op == 2:  # the whole joint deprecated
            repo.deprecate(name, None, reason="test")
        elif op == 3:  # one version deprecated (the newest)
            repo.deprecate(name, repo.history(name)[-1].version, reason="test")
        elif op == 4:  # undone
            repo.deprecate(name, None, reason="test", undo=True)
        else:
            repo.label(name, repo.history(name)[0].version, "released")
        _check(repo, names, types)
    assert len(names) >= 3 and seen == set(range(6))


def test_a_new_version_of_a_wholly_deprecated_joint_is_listed_deprecated(repo):
    repo.catalogue("D1", "tool-holder", spring_joint(), planar_conditions(), KIND)
    repo.deprecate("D1", None, reason="gone")
    repo.catalogue("D1", "tool-holder", spring_joint(k=(3e6, 8e4)), planar_conditions(), KIND)
    _check(repo, {"D1"}, {"D1": "tool-holder"})
    assert [(v.version, v.state) for v in repo.list_page().items] == [(2, "deprecated")]
    repo.deprecate("D1", None, reason="back", undo=True)
    repo.deprecate("D1", 2, reason="v2 bad")
    _check(repo, {"D1"}, {"D1": "tool-holder"})
    assert [(v.version, v.state) for v in repo.list_page().items] == [(1, "active")]
    repo.catalogue("D1", "tool-holder", spring_joint(k=(4e6, 8e4)), planar_conditions(), KIND)
    _check(repo, {"D1"}, {"D1": "tool-holder"})
    assert [(v.version, v.state) for v in repo.list_page().items] == [(3, "active")]


def test_a_filtered_total_is_counted_once_and_carried_in_the_cursor(repo):
    for i in range(5):
        repo.catalogue(f"C{i}", "tool-holder", spring_joint(), planar_conditions(torque=10.0 + i), KIND)
    first = repo.list_page(torque_min=11.0, limit=2)
    assert [v.name for v in first.items] == ["C1", "C2"] and first.total == 4
    repo.catalogue("C9", "tool-holder", spring_joint(), planar_conditions(torque=50.0), KIND)
    second = repo.list_page(torque_min=11.0, limit=2, after=first.next)
    assert [v.name for v in second.items] == ["C3", "C4"] and second.total == 4  # as when the listing started
    assert repo.list_page(torque_min=11.0, limit=2).total == 5  # a new listing counts again
    last = repo.list_page(torque_min=11.0, limit=2, after=second.next)
    assert [v.name for v in last.items] == ["C9"] and last.next is None


def test_migration_0010_fills_the_head_for_existing_data(backend):
    repo = backend.repo()
    try:
        for i, jtype in enumerate(("tool-holder", "holder-spindle", "tool-holder")):
            repo.catalogue(f"M{i}", jtype, spring_joint(), planar_conditions(), KIND)
            repo.catalogue(f"M{i}", jtype, spring_joint(k=(3e6, 8e4)), planar_conditions(), KIND)
        repo.deprecate("M0", 2, reason="x")  # listed: v1 (active)
        repo.deprecate("M1", None, reason="x")  # listed: v2 (deprecated)
        before = [(v.name, v.version, v.state) for v in repo.list_page().items]
    finally:
        repo.close()
    assert before == [("M0", 1, "active"), ("M1", 2, "deprecated"), ("M2", 2, "active")]
    assert downgrade(backend.url, "0009") == "0009"
    engine = sa.create_engine(backend.url)
    try:
        with engine.connect() as conn:
            cols = {c["name"] for c in sa.inspect(conn).get_columns("query_versions")}
            assert "listed" not in cols and not sa.inspect(conn).has_table("query_counts")
    finally:
        engine.dispose()
    upgrade(backend.url)
    repo = backend.repo()
    try:
        with repo.read_engine.connect() as conn:
            assert index_problems(conn) == []
        page = repo.list_page(limit=2)
        assert [(v.name, v.version, v.state) for v in page.items] == before[:2] and page.total == 3
        assert repo.list_page(include_deprecated=False).total == 2
    finally:
        repo.close()


@pytest.mark.parametrize("joint_type", [None, "tool-holder"])
def test_a_page_is_one_range_of_the_head_index(repo, joint_type):
    """The plan of a page reads the (type,) listed, name index in order: no sort, no full scan."""
    from jointdb.store._listing import page_statement

    for i in range(30):
        repo.catalogue(f"P{i:02d}", "tool-holder", spring_joint(), planar_conditions(), KIND)
    filters = dict(joint_type=joint_type, materials=(), label=None, include_deprecated=True, state=None,
                   torque=(None, None), preload=(None, None), name_contains=None)
    with repo.read_engine.connect() as conn:
        stmt = page_statement(conn.dialect.name, after="P10", offset=0, limit=5, with_total=False, **filters)
        sql = str(stmt.compile(dialect=conn.dialect, compile_kwargs={"literal_binds": True}))
        if conn.dialect.name == "sqlite":
            plan = " | ".join(str(r[-1]) for r in conn.exec_driver_sql("EXPLAIN QUERY PLAN " + sql))
            assert "listed_name" in plan and "TEMP B-TREE" not in plan, plan
        else:
            # 30 rows: force what 100k rows choose for a LIMIT read in index order — no full scan, and a nested loop
            # into joint_versions (on so few rows the planner may otherwise pick a merge join, which sorts by id)
            for setting in ("enable_seqscan", "enable_bitmapscan", "enable_mergejoin", "enable_hashjoin"):
                conn.exec_driver_sql(f"SET {setting} = off")
            plan = " | ".join(r[0] for r in conn.exec_driver_sql("EXPLAIN " + sql))
            assert "listed_name" in plan and "Sort" not in plan, plan


def test_an_analyzed_sqlite_database_still_opens(tmp_path):
    """ANALYZE (planner statistics, which the listing's plans rely on at scale) adds SQLite's own
    sqlite_stat1 table; jointdb must not take it for a foreign table."""
    from jointdb.store import Repository

    repo = Repository(tmp_path / "a.sqlite")
    repo.catalogue("A1", "tool-holder", spring_joint(), planar_conditions(), KIND)
    with repo.write_engine.connect() as conn:
        conn.exec_driver_sql("ANALYZE")
        conn.commit()
        assert conn.exec_driver_sql("SELECT count(*) FROM sqlite_master WHERE name = 'sqlite_stat1'").scalar() == 1
    repo.close()
    again = Repository(tmp_path / "a.sqlite")
    assert [v.name for v in again.list_page().items] == ["A1"]
    again.close()


def test_the_fast_check_of_a_stored_field_accepts_only_what_the_full_check_accepts():
    """Reading a row skips walking a flat JSON field only when the full check would pass it; anything
    it is unsure of (nesting, NaN, infinity, huge integers, non-text keys, long texts) is checked in full."""
    from jointdb.errors import InputError
    from jointdb.schemas._limits import check_stored_json
    from jointdb.store._records import MAX_RECORD_BYTES, _flat_within_limits

    def full_ok(value) -> bool:
        try:
            check_stored_json(value, "f", max_bytes=MAX_RECORD_BYTES, texts=False)
        except InputError:
            return False
        return True

    rng = np.random.default_rng(5)
    pool = [0, -1, 2.5, 1e300, -1e300, 1e301, float("nan"), float("inf"), 10**400, True, None, "", "x\u00e9\n",
            "y" * 10, {"a": 1}, [1], "z" * (MAX_RECORD_BYTES // 5)]
    fast_hits = 0
    for _ in range(400):
        items = [pool[int(i)] for i in rng.integers(len(pool), size=int(rng.integers(0, 5)))]
        value = {f"k{i}": x for i, x in enumerate(items)} if rng.random() < 0.5 else items
        if _flat_within_limits(value):
            fast_hits += 1
            assert full_ok(value), value
    assert fast_hits > 50
    for bad in ([float("nan")], {"a": float("inf")}, [10**400], {"a": {"b": 1}}, [[1]], {1: "a"}):
        assert not _flat_within_limits(bad)
    assert _flat_within_limits({"diameter_m": 0.02, "taper": "HSK-A63", "ok": True, "none": None})


def test_deprecate_waits_for_the_joint_row_lock_a_catalogue_holds(repo):
    """A catalogue reads whether the listed version is deprecated under the joint's row lock (``FOR UPDATE``); a
    deprecation of the same joint must wait for that lock, or it could commit between that read and the catalogue's
    write. It does: its state row's foreign key takes ``FOR KEY SHARE`` on the joint row, which conflicts."""
    import threading

    if repo.write_engine.dialect.name != "postgresql":
        pytest.skip("SQLite serialises writers with the database lock; the row lock is PostgreSQL's")
    repo.catalogue("L1", "tool-holder", spring_joint(), planar_conditions(), KIND)
    done = threading.Event()
    with repo.write_engine.connect() as other:
        tx = other.begin()
        other.execute(sa.text("SELECT id FROM joints WHERE name = 'L1' FOR UPDATE"))  # as a catalogue of L1 holds it
        worker = threading.Thread(target=lambda: (repo.deprecate("L1", None, reason="gone"), done.set()))
        worker.start()
        assert not done.wait(1.5), "deprecate went ahead while the joint row was locked"
        tx.rollback()
    worker.join(30)
    assert done.is_set()
    _check(repo, {"L1"}, {"L1": "tool-holder"})
    assert [(v.version, v.state) for v in repo.list_page().items] == [(1, "deprecated")]
