"""Helpers shared by the storage tests (imported by name; pytest puts this directory on sys.path)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointdb.frf import FRF


def spring_joint(k=(2e6, 8e4), c=(100.0, 80.0), dofs=("3x", "3ry"), freq=None, n=64):
    """Diagonal spring-damper joint receptance diag(1/(k + iωc)) (theory.md §1a)."""
    f = np.linspace(10.0, 2000.0, n) if freq is None else np.asarray(freq, float)
    w = 2 * np.pi * f
    h = np.zeros((f.size, len(dofs), len(dofs)), complex)
    for i, (ki, ci) in enumerate(zip(k, c)):
        h[:, i, i] = 1.0 / (ki + 1j * w * ci)
    return FRF(f, h, list(dofs), list(dofs))


def planar_conditions(torque=40.0, materials=("tungsten-carbide", "steel"), **kw):
    from jointdb.store import Conditions

    return Conditions(materials=materials, torque_nm=torque, **kw)


def count_rows(backend_or_repo) -> dict[str, int]:
    import sqlalchemy as sa

    repo = backend_or_repo
    out = {}
    with repo.read_engine.connect() as conn:
        for t in ("joints", "joint_versions", "labels", "joint_states", "audit_log"):
            out[t] = conn.execute(sa.text(f"SELECT count(*) FROM {t}")).scalar_one()
    return out


def blob_files(repo) -> list[str]:
    return sorted(p.name for p in Path(repo.blobs.root).glob("*/*")) if Path(repo.blobs.root).exists() else []


def reseal(path) -> None:
    """Recompute a blob file's whole-file checksum after a deliberate edit (simulates a
    file that is internally consistent but carries bad content)."""
    import hashlib

    from jointdb.store._blobs import USERBLOCK, _userblock

    data = Path(path).read_bytes()
    Path(path).write_bytes(_userblock(hashlib.sha256(data[USERBLOCK:]).hexdigest()) + data[USERBLOCK:])
