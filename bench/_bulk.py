"""Bulk filler for store benchmarks: many versions written fast through the real tables.

Rows go into ``joints`` and ``joint_versions`` (with true record hashes, so every
read verifies them as usual) and a few ``joint_states`` / ``labels`` rows, with
executemany in one transaction each; the query index is then built from them by
the same function migration 0004 uses (:func:`jointdb.store._index.rebuild`, which also
fills the listing's head and counts of migration 0010), and the tables are ANALYZEd.
No blob files exist: a query that touched a blob would fail.
"""

from __future__ import annotations

import math
import uuid
from datetime import datetime, timedelta, timezone
from types import SimpleNamespace

import numpy as np

TYPES = ("tool-holder", "holder-spindle")
MATERIAL_SETS = (["tungsten-carbide", "steel"], ["steel", "steel"], ["hardened-steel", "steel"])


def _rows(n_versions: int, per_joint: int, seed: int) -> tuple[list, list, list, list]:
    """``(joints, versions, states, labels)`` row dicts (versions with ids and true record hashes)."""
    from jointdb.store._records import record_dict, record_sha256

    rng = np.random.default_rng(seed)
    n_joints = n_versions // per_joint
    t0 = datetime(2026, 1, 1, tzinfo=timezone.utc)
    joints, versions, states, labels = [], [], [], []
    torque = np.exp(rng.uniform(math.log(5), math.log(300), n_versions))
    preload = rng.uniform(1e3, 5e4, n_versions)
    diameter = rng.uniform(0.006, 0.04, n_versions)
    mats = rng.integers(len(MATERIAL_SETS), size=n_versions)
    i = 0
    for j in range(n_joints):
        name, jtype = f"bulk-{j:07d}", TYPES[j % 2]
        joints.append({"id": j + 1, "name": name, "joint_type": jtype, "created_at": t0, "created_by": "bench"})
        for v in range(1, per_joint + 1):
            row = SimpleNamespace(
                joint_id=j + 1, version=v, uuid=str(uuid.UUID(int=int(rng.integers(1 << 62)) << 64 | i)),
                created_at=t0 + timedelta(seconds=i), author="bench", materials=MATERIAL_SETS[mats[i]],
                preload_n=float(preload[i]), torque_nm=float(torque[i]), geometry={"diameter_m": float(diameter[i])},
                extra={}, model_kind="spring-damper-planar", dofs=["3x", "3ry"], quantity="receptance", n_freq=1000,
                freq_min_hz=10.0, freq_max_hz=5000.0, blob_sha256="0" * 64, raw_blobs={}, input_files={},
                method="bulk", method_params={}, software_version="bench", parent_version=v - 1 if v > 1 else None,
                quality={})
            row.record_sha256 = record_sha256(record_dict(name, jtype, row))
            row.id = i + 1
            versions.append(vars(row))
            i += 1
        at = t0 + timedelta(days=30, seconds=j)
        if j % 50 == 49:
            states.append({"joint_id": j + 1, "version": None, "state": "deprecated", "reason": "bench",
                           "author": "bench", "at": at})
        elif j % 7 == 6 and per_joint > 1:
            states.append({"joint_id": j + 1, "version": per_joint, "state": "deprecated", "reason": "bench",
                           "author": "bench", "at": at})
        if j % 3 == 0:
            labels.append({"joint_id": j + 1, "label": "released", "version": 1, "updated_at": at,
                           "updated_by": "bench"})
    return joints, versions, states, labels


def bulk_fill(repo, n_versions: int, per_joint: int, seed: int = 7) -> None:
    """``n_versions`` versions, ``per_joint`` per joint, joints alternating between two types;
    every 50th joint deprecated as a whole, every 7th joint's newest version deprecated, every
    3rd joint's first version labelled ``released``."""
    from jointdb.store._index import rebuild
    from jointdb.store._models import JointRow, LabelRow, StateRow, VersionRow

    joints, versions, states, labels = _rows(n_versions, per_joint, seed)
    for v in versions:
        del v["id"]
    with repo.write_engine.begin() as conn:
        conn.execute(JointRow.__table__.insert(), joints)
        for k in range(0, len(versions), 20_000):
            conn.execute(VersionRow.__table__.insert(), versions[k:k + 20_000])
        if states:
            conn.execute(StateRow.__table__.insert(), states)
        if labels:
            conn.execute(LabelRow.__table__.insert(), labels)
        rebuild(conn)
    with repo.write_engine.connect() as conn:  # planner statistics, as autovacuum / a routine ANALYZE keep them
        conn.exec_driver_sql("ANALYZE")
        conn.commit()


def _index_rows(joints: list, versions: list, states: list) -> tuple[list, list]:
    """The query index rows of the bulk rows, by the functions the catalogue and rebuild use
    (:func:`jointdb.store._index.standing`, :func:`~jointdb.store._index.index_values`)."""
    from jointdb.store._index import index_values, standing

    per_joint: dict[int, list] = {}
    for v in versions:
        per_joint.setdefault(v["joint_id"], []).append(v)
    joint_states: dict[int, list] = {}
    for n, s in enumerate(states, start=1):
        joint_states.setdefault(s["joint_id"], []).append((s["at"], n, s["version"], s["state"]))
    rows, geo = [], []
    for j in joints:
        vs = per_joint.get(j["id"], [])
        flags = standing([(v["id"], v["version"]) for v in vs], joint_states.get(j["id"], ()))
        for v in vs:
            row, g = index_values(v["id"], (j["id"], j["name"], j["joint_type"]), v["version"], v["materials"],
                                  v["torque_nm"], v["preload_n"], v["geometry"], flags[v["id"]])
            rows.append(row)
            geo.extend(g)
    return rows, geo


def _copy(cur, table: str, rows: list[dict], json_columns: tuple[str, ...] = ()) -> None:
    import json

    if not rows:
        return
    cols = list(rows[0])
    with cur.copy(f"COPY {table} ({', '.join(cols)}) FROM STDIN") as copy:
        for r in rows:
            copy.write_row([json.dumps(r[c]) if c in json_columns else r[c] for c in cols])


def bulk_fill_copy(url: str, n_versions: int, per_joint: int, seed: int = 7) -> None:
    """:func:`bulk_fill` on a migrated PostgreSQL schema through ``COPY`` (a million versions in
    about a minute): the same history rows, and the query index rows computed from them by the
    functions the catalogue and the rebuild use; the listing counts by the SQL of migration
    ``0010``; the stamp moved to a generation without a change-log entry (readers refetch); serial
    sequences advanced past the ids given; ANALYZE."""
    import psycopg

    from jointdb.store._light import _libpq

    joints, versions, states, labels = _rows(n_versions, per_joint, seed)
    for n, s in enumerate(states, start=1):
        s["id"] = n
    index, geo = _index_rows(joints, versions, states)
    json_cols = ("materials", "geometry", "extra", "dofs", "raw_blobs", "input_files", "method_params", "quality")
    conninfo, kw = _libpq(url)
    with psycopg.connect(conninfo, **kw) as conn:
        with conn.cursor() as cur:
            _copy(cur, "joints", joints)
            _copy(cur, "joint_versions", versions, json_cols)
            _copy(cur, "joint_states", states)
            _copy(cur, "labels", labels)
            _copy(cur, "query_versions", index)
            _copy(cur, "query_geometry", geo)
            cur.execute("DELETE FROM query_counts")
            cur.execute("INSERT INTO query_counts (joint_type, deprecated, joints) SELECT joint_type, deprecated, "
                        "COUNT(*) FROM query_versions WHERE listed GROUP BY joint_type, deprecated")
            cur.execute("UPDATE query_stamp SET generation = generation + 1 WHERE id = 1")
            for table in ("joints", "joint_versions", "joint_states", "labels"):
                cur.execute(f"SELECT setval(pg_get_serial_sequence('{table}', 'id'), "
                            f"(SELECT coalesce(max(id), 0) + 1 FROM {table}), false)")
        conn.commit()
        conn.autocommit = True
        conn.execute("ANALYZE")
