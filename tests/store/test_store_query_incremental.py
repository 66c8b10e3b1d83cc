"""The query cache updated incrementally equals a full fetch, bit for bit (SQLite and PostgreSQL).

After each random write (new versions of new and existing joints, labels moved and removed, an import,
versions and whole joints deprecated and undone) every selection's candidate arrays are taken
as the next query takes them — from the arrays of the previous generation (this process's
cache, or the on-disk file of a "new process") updated with the rows of the changed joints —
and compared with a fresh full fetch in the same snapshot, byte for byte. A spy checks that the
update really was incremental; a rebuild, a pruned log, a damaged file and a new token must
fall back to a full fetch (and still give the same arrays).
"""

from __future__ import annotations

import random
import warnings

import pytest
from store_helpers import spring_joint

from jointdb.store import Conditions, Repository
from jointdb.store import _nearest
from jointdb.store._nearest import Reader, Selection

SELECTIONS = [Selection("tool-holder", label, all_versions, include_deprecated)
              for label in (None, "released") for all_versions in (False, True)
              for include_deprecated in (False, True)]
KEYS = ["diameter_m"]
FIELDS = ("version_id", "joint_id", "number", "torque", "preload", "materials_index")


def _assert_same(a, b) -> None:
    for f in FIELDS:
        x, y = getattr(a, f), getattr(b, f)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), f
    assert a.materials == b.materials
    assert sorted(a.geometry) == sorted(b.geometry)
    for k in a.geometry:
        assert a.geometry[k].tobytes() == b.geometry[k].tobytes(), k


class Spy:
    """Records the joint ids of every fetch the cache makes (None: a full fetch)."""

    def __init__(self, monkeypatch):
        self.real = _nearest._fetch
        self.calls: list = []
        monkeypatch.setattr(_nearest, "_fetch", self)

    def __call__(self, reader, sel, keys, joint_ids=None):
        self.calls.append(None if joint_ids is None else tuple(joint_ids))
        return self.real(reader, sel, keys, joint_ids)


def _check_all(repo, spy, fresh_process: bool, expect: str) -> None:
    """Every selection through the cache vs. a full fetch, in one snapshot each.

    ``expect``: ``"incremental"`` (no full fetch by the cache), ``"full"`` or ``"any"``."""
    if fresh_process:
        _nearest._cache.clear()
    raw = repo.read_engine.raw_connection()
    try:
        reader = Reader(raw, repo.read_engine.dialect.name)
        for sel in SELECTIONS:
            spy.calls.clear()
            with reader.snapshot():
                got = _nearest.current_candidates(reader, repo.url, sel, KEYS)
                cache_calls = list(spy.calls)
                want = spy.real(reader, sel, KEYS)
            _assert_same(got, want)
            if expect == "incremental":
                assert None not in cache_calls, (sel, cache_calls)
            elif expect == "full":
                assert cache_calls == [None], (sel, cache_calls)
    finally:
        raw.close()


def _random_write(repo, rnd: random.Random, names: list[str]) -> None:
    op = rnd.choice(("new joint", "version", "version", "label", "unlabel", "deprecate version",
                     "deprecate joint", "undo joint"))
    if op == "new joint" or not names:
        name, op = f"N{len(names)}", "version"
        names.append(name)
    else:
        name = rnd.choice(names)
    n = len(repo.history(name)) if op != "version" else 0
    if op == "version":
        geometry = {"diameter_m": rnd.choice((0.02, 0.032))} if rnd.random() < 0.7 else {}
        repo.catalogue(name, "tool-holder", spring_joint(), Conditions(
            rnd.choice(((), ("steel",), ("tungsten-carbide", "steel"), (rnd.choice(("brass", "bronze", "titanium", "aluminium")),))),
            torque_nm=rnd.choice((10.0, 20.0, None, 80.0)), preload_n=rnd.choice((None, 1e4)), geometry=geometry),
            "spring-damper-planar", force=True)
    elif op == "label":
        repo.label(name, rnd.randint(1, n), "released")
    elif op == "unlabel":
        if any("released" in v.labels for v in repo.history(name)):
            repo.unlabel(name, "released")
    elif op == "deprecate version":
        repo.deprecate(name, rnd.randint(1, n), reason="bad fit")
    elif op == "deprecate joint":
        repo.deprecate(name, reason="withdrawn")
    elif repo.get(name).state == "deprecated":
        repo.deprecate(name, undo=True)


@pytest.mark.parametrize("seed", [5])
def test_incremental_update_equals_a_full_fetch(repo, tmp_path, monkeypatch, seed):
    monkeypatch.setenv("JOINTDB_QUERY_CACHE", str(tmp_path / "cache"))
    _nearest._cache.clear()
    spy = Spy(monkeypatch)
    rnd = random.Random(seed)
    names: list[str] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(4):
            _random_write(repo, rnd, names)
        _check_all(repo, spy, fresh_process=False, expect="full")
        for step in range(14):
            for _ in range(rnd.randint(1, 2)):
                _random_write(repo, rnd, names)
            _check_all(repo, spy, fresh_process=step % 2 == 1, expect="incremental")
        repo.catalogue("other", "holder-spindle", spring_joint(), Conditions(torque_nm=20.0), "spring-damper-planar")
        _check_all(repo, spy, fresh_process=True, expect="incremental")  # another type: no row of ours changed
        with Repository(tmp_path / "lab.sqlite") as lab:  # an import adds joints and versions in one transaction
            for i, t in enumerate((15.0, 35.0)):
                lab.catalogue(f"IMP{i}", "tool-holder", spring_joint(), Conditions(("steel",), torque_nm=t),
                              "spring-damper-planar")
            lab.label("IMP1", 1, "released")
            lab.export(None, tmp_path / "lab.h5")
        repo.import_(tmp_path / "lab.h5", force=True)
        _check_all(repo, spy, fresh_process=False, expect="incremental")


def _write_and_check(repo, spy, rnd, names, expect, fresh_process=False):
    _random_write(repo, rnd, names)
    _check_all(repo, spy, fresh_process=fresh_process, expect=expect)


def test_gaps_damage_and_rebuilds_fall_back_to_a_full_fetch(repo, tmp_path, monkeypatch):
    from jointdb.store._index import rebuild

    cache = tmp_path / "cache"
    monkeypatch.setenv("JOINTDB_QUERY_CACHE", str(cache))
    _nearest._cache.clear()
    spy = Spy(monkeypatch)
    rnd = random.Random(2)
    names: list[str] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(5):
            _random_write(repo, rnd, names)
        _check_all(repo, spy, fresh_process=False, expect="full")
        _write_and_check(repo, spy, rnd, names, "incremental")
        _random_write(repo, rnd, names)
        with repo.write_engine.begin() as conn:  # the log pruned past the cached generation: a gap
            conn.exec_driver_sql("DELETE FROM query_changes")
        _write_and_check(repo, spy, rnd, names, "full")
        for f in cache.glob("*.npz"):  # damaged older files: never trusted
            f.write_bytes(f.read_bytes()[: len(f.read_bytes()) // 2])
        _write_and_check(repo, spy, rnd, names, "full", fresh_process=True)
        with repo.write_engine.begin() as conn:  # rebuilt index: a generation without a log entry
            rebuild(conn)
        _check_all(repo, spy, fresh_process=False, expect="full")
        with repo.write_engine.begin() as conn:  # another token (e.g. a restored database): refetch
            conn.exec_driver_sql("UPDATE query_stamp SET token = 'another-token'")
        _write_and_check(repo, spy, rnd, names, "full")
        _write_and_check(repo, spy, rnd, names, "incremental", fresh_process=True)


def test_the_change_log_is_pruned_to_the_last_generations(repo):
    from jointdb.store._index import KEEP_GENERATIONS, PRUNE_EVERY

    repo.catalogue("P", "tool-holder", spring_joint(), Conditions(torque_nm=10.0), "spring-damper-planar")
    with repo.write_engine.begin() as conn:
        generation = 2 * KEEP_GENERATIONS - 1  # the next write's generation is a multiple of PRUNE_EVERY
        conn.exec_driver_sql(f"UPDATE query_stamp SET generation = {generation}")
        conn.exec_driver_sql(f"INSERT INTO query_changes (generation, joint_id) VALUES ({KEEP_GENERATIONS}, 1), "
                             f"({KEEP_GENERATIONS + 1}, 1)")
    assert (generation + 1) % PRUNE_EVERY == 0
    repo.label("P", 1, "released")
    with repo.read_engine.connect() as conn:
        kept = [tuple(r) for r in conn.exec_driver_sql("SELECT generation, joint_id FROM query_changes "
                                                       "ORDER BY generation")]
    # P's own first entry (generation 1) and everything up to KEEP_GENERATIONS back are gone; P is joint 1
    assert kept == [(KEEP_GENERATIONS + 1, 1), (generation + 1, 1)]
