"""The nearest query over the query index equals the straightforward formula.

A catalogue with several versions per joint, labels, deprecated versions and
joints (some undone), tied conditions and missing values is built through the
public API; every selection (default, ``label``, ``all_versions``,
``include_deprecated`` and their combinations) is ranked by the library and by a
plain-Python reference written from the documented definition over the records
``history()`` returns. The fast path must also equal the history path
(:func:`candidates_from_history`) bit for bit, and the index must equal what
``db check`` recomputes from history.
"""

from __future__ import annotations

import math
import random
import warnings
from collections import Counter

import pytest
from store_helpers import spring_joint

from jointdb.errors import InputError, NotFoundError
from jointdb.store import Conditions, OutsideCatalogueWarning
from jointdb.store._nearest import Selection
from jointdb.store._rank import rank
from jointdb.store._query import candidates_from_history

TORQUES = (10.0, 20.0, 20.0, 40.0, None, 80.0)  # 20 twice: ties
MATERIALS = ((), ("steel",), ("tungsten-carbide", "steel"), ("steel", "steel"))


@pytest.fixture
def catalogue(repo):
    rnd = random.Random(11)
    order: list[str] = []
    for j in range(9):
        name = f"J{j}"
        for _ in range(rnd.randint(1, 4)):
            torque = rnd.choice(TORQUES)
            geometry = {"diameter_m": rnd.choice((0.02, 0.032))} if rnd.random() < 0.7 else {}
            repo.catalogue(name, "tool-holder", spring_joint(), Conditions(
                rnd.choice(MATERIALS), torque_nm=torque, preload_n=rnd.choice((None, 1e4, 3e4)),
                geometry=geometry), "spring-damper-planar", force=True)
        order.append(name)
        n = len(repo.history(name))
        if rnd.random() < 0.6:
            repo.label(name, rnd.randint(1, n), "released")
        if n > 1 and rnd.random() < 0.5:
            repo.deprecate(name, n, reason="bad fit")  # the newest: an older one is current again
        if rnd.random() < 0.2:
            repo.deprecate(name, reason="withdrawn")  # the whole joint
            if rnd.random() < 0.5:
                repo.deprecate(name, undo=True)
    repo.catalogue("other", "holder-spindle", spring_joint(), Conditions(torque_nm=20.0), "spring-damper-planar")
    return repo, order


def _selected(repo, order, label, all_versions, include_deprecated):
    """(joint rank, version) of the selection, from the records history() returns."""
    out = []
    for rank_, name in enumerate(order):
        kept = [v for v in repo.history(name)
                if (include_deprecated or v.state == "active") and (label is None or label in v.labels)]
        if kept and not all_versions:
            kept = [max(kept, key=lambda v: v.version)]
        out.extend((rank_, v) for v in kept)
    return out


def _jaccard(a, b):
    ca, cb = Counter(a), Counter(b)
    union = sum((ca | cb).values())
    return 0.0 if union == 0 else 1.0 - sum((ca & cb).values()) / union


def _reference(cands, req: Conditions, k: int):
    """The documented distance, one candidate at a time, in plain Python."""
    def log_terms(attr, r):
        vals = [getattr(v.conditions, attr) for _, v in cands]
        have = [x for x in vals if x is not None]
        if not have:
            return [1.0] * len(vals)
        delta = 1e-9 * max(1.0, max(have))
        logs = [math.log(x + delta) for x in have]
        spread = max(max(logs) - min(logs), math.log(2.0))
        return [1.0 if x is None else abs(math.log(x + delta) - math.log(r + delta)) / spread for x in vals]

    terms = {}
    if req.torque_nm is not None:
        terms["torque_nm"] = log_terms("torque_nm", req.torque_nm)
    if req.preload_n is not None:
        terms["preload_n"] = log_terms("preload_n", req.preload_n)
    if req.materials:
        terms["materials"] = [_jaccard(sorted(req.materials), sorted(v.conditions.materials))
                              if v.conditions.materials else 1.0 for _, v in cands]
    for key, r in req.geometry.items():
        col = []
        for _, v in cands:
            c = v.conditions.geometry.get(key)
            col.append(1.0 if c is None else (abs(c - r) / max(abs(c), abs(r)) if max(abs(c), abs(r)) > 0 else 0.0))
        terms[f"geometry.{key}"] = col
    total = [math.sqrt(sum(t[i] ** 2 for t in terms.values())) for i in range(len(cands))]
    ranked = sorted(range(len(cands)), key=lambda i: (round(total[i], 12), cands[i][0], cands[i][1].version))
    return [(cands[i][1].name, cands[i][1].version, total[i], cands[i][1].state) for i in ranked[:k]]


REQUESTS = [
    Conditions(torque_nm=20.0),
    Conditions(("tungsten-carbide", "steel"), torque_nm=33.0, geometry={"diameter_m": 0.025}),
    Conditions(("steel",), preload_n=2e4, geometry={"diameter_m": 0.032}),
    Conditions(("steel", "steel"), torque_nm=500.0, preload_n=1e4),
]
SELECTIONS = [(label, all_v, inc) for label in (None, "released") for all_v in (False, True) for inc in (False, True)]


@pytest.mark.parametrize("label, all_versions, include_deprecated", SELECTIONS)
def test_fast_path_equals_the_plain_formula(catalogue, label, all_versions, include_deprecated):
    repo, order = catalogue
    cands = _selected(repo, order, label, all_versions, include_deprecated)
    assert cands, "the fixture must leave something in every selection"
    for req in REQUESTS:
        for k in (1, 3, 50):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", OutsideCatalogueWarning)
                got = repo.nearest("tool-holder", req, k=k, label=label, all_versions=all_versions,
                                   include_deprecated=include_deprecated)
            want = _reference(cands, req, k)
            assert [(m.version.name, m.version.version, m.version.state) for m in got] == \
                [(n, v, s) for n, v, _, s in want]
            for m, (_, _, d, _) in zip(got, want):
                # sums of a few squared terms of size <= 1, each from logs/divisions: round-off only
                assert m.distance == pytest.approx(d, rel=1e-13, abs=1e-15)
            if label is not None:
                assert all(label in m.version.labels for m in got)


@pytest.mark.parametrize("label, all_versions, include_deprecated", SELECTIONS)
def test_index_equals_history_bit_for_bit(catalogue, label, all_versions, include_deprecated):
    repo, _ = catalogue
    sel = Selection("tool-holder", label, all_versions, include_deprecated)
    req = REQUESTS[1]
    cand, _ = candidates_from_history(repo, sel, None, ["diameter_m"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideCatalogueWarning)
        order, total, _, _ = rank(cand, req, 1000)
        got = repo.nearest("tool-holder", req, k=1000, label=label, all_versions=all_versions,
                           include_deprecated=include_deprecated)
    assert len(got) == len(order)
    assert [m.distance for m in got] == [float(total[i]) for i in order]  # exactly


def test_index_follows_every_write_and_db_check_agrees(catalogue, backend):
    repo, _ = catalogue
    from jointdb.store._index import index_problems

    with repo.read_engine.connect() as conn:
        assert index_problems(conn) == []
    assert repo.check(verify_blobs=False).ok
    # a tampered index row is reported by db check
    with repo.write_engine.begin() as conn:
        conn.exec_driver_sql("UPDATE query_versions SET torque_nm = 1234.5 WHERE version_id = 1")
    report = repo.check(verify_blobs=False)
    assert not report.ok and any("query index" in p for p in report.problems)


def test_selection_errors(catalogue):
    repo, _ = catalogue
    with pytest.raises(NotFoundError, match="labelled 'nope'"):
        repo.nearest("tool-holder", Conditions(torque_nm=20.0), label="nope")
    with pytest.raises(InputError, match="--label with --at"):
        repo.nearest("tool-holder", Conditions(torque_nm=20.0), label="released", at="2020-01-01T00:00:00Z")


@pytest.mark.parametrize("all_versions, include_deprecated", [(False, False), (False, True), (True, False), (True, True)])
def test_point_in_time_path_equals_the_index_after_the_last_write(catalogue, all_versions, include_deprecated):
    repo, _ = catalogue
    kw = {"k": 50, "all_versions": all_versions, "include_deprecated": include_deprecated}
    for req in REQUESTS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutsideCatalogueWarning)
            now = repo.nearest("tool-holder", req, **kw)
            later = repo.nearest("tool-holder", req, at="2100-01-01T00:00:00Z", **kw)
        assert [(m.version.name, m.version.version, m.version.state, m.distance) for m in now] == \
            [(m.version.name, m.version.version, m.version.state, m.distance) for m in later]


@pytest.mark.parametrize("label, all_versions, include_deprecated", SELECTIONS)
def test_raw_and_hex_fetches_give_the_same_candidates(catalogue, label, all_versions, include_deprecated, monkeypatch):
    """SQLite hands the packed columns over as raw bytes (a BLOB concatenated as text); the hex
    form (taken when the raw one does not line up, e.g. a UTF-16 database) gives the same arrays."""
    import numpy as np

    import jointdb.store._nearest as nearest

    repo, _ = catalogue
    if not repo.is_sqlite:
        pytest.skip("the packed fetch is SQLite's")
    sel = Selection("tool-holder", label, all_versions, include_deprecated)
    keys = ["diameter_m", "length_m"]  # the second key no version has: all NULL
    raw = repo.read_engine.raw_connection()
    try:
        reader = nearest.Reader(raw, "sqlite")
        with reader.snapshot():
            a = nearest._packed_row(reader, sel, keys, raw=True)
            b = nearest._packed_row(reader, sel, keys, raw=False)
            assert a[0] > 0 and a == b
            want = nearest._fetch(reader, sel, keys)
            real = nearest._packed_row

            def short_raw(reader_, sel_, keys_, raw, joint_ids=None):  # raw bytes cut short: the hex form is used
                n, binary, mats = real(reader_, sel_, keys_, raw, joint_ids)
                return (n, [x[:-1] for x in binary], mats) if raw else (n, binary, mats)

            monkeypatch.setattr(nearest, "_packed_row", short_raw)
            got = nearest._fetch(reader, sel, keys)
    finally:
        raw.close()
    for field in ("version_id", "joint_id", "number", "torque", "preload", "materials_index"):
        assert np.array_equal(getattr(got, field), getattr(want, field), equal_nan=field in ("torque", "preload"))
    assert got.materials == want.materials
    for key in keys:
        assert np.array_equal(got.geometry[key], want.geometry[key], equal_nan=True)
    assert np.isnan(want.geometry["length_m"]).all() and not np.isnan(want.geometry["diameter_m"]).all()
