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


def bulk_fill(repo, n_versions: int, per_joint: int, seed: int = 7) -> None:
    """``n_versions`` versions, ``per_joint`` per joint, joints alternating between two types;
    every 50th joint deprecated as a whole, every 7th joint's newest version deprecated, every
    3rd joint's first version labelled ``released``."""
    from jointdb.store._index import rebuild
    from jointdb.store._models import JointRow, LabelRow, StateRow, VersionRow
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
        name, jtype = f"bulk-{j:06d}", TYPES[j % 2]
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
