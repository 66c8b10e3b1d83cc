"""Helpers shared by the storage tests (imported by name; pytest puts this directory on sys.path)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointdb.frf import FRF


def spring_joint(k=(2e6, 8e4), c=(100.0, 80.0), dofs=("3x", "3ry"), freq=None, n=64):
    """Diagonal spring-damper joint receptance diag(1/(k + iωc)) (docs/theory.md §1a)."""
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


def run_cli(*args, env: dict | None = None, input: str | None = None):
    """The real entry point in a subprocess: ``(returncode, stdout, stderr)``."""
    import os
    import subprocess
    import sys

    full_env = {**os.environ, **(env or {})}
    out = subprocess.run([sys.executable, "-m", "jointdb", *map(str, args)], capture_output=True, text=True,
                         env=full_env, input=input, timeout=300)
    return out.returncode, out.stdout, out.stderr


def assert_one_line_error(result, code: int, contains: str = "") -> str:
    """Exit ``code``, exactly one line on stderr starting with ``error:``, no traceback."""
    rc, _, err = result
    lines = err.strip().splitlines()
    assert rc == code and len(lines) == 1 and lines[0].startswith("error: "), (rc, err)
    assert "Traceback" not in err and contains in lines[0], err
    return lines[0]


def alter_version_row(url: str, sql: str, table: str = "joint_versions") -> None:
    """Change a history row behind jointdb's back (what an adversary with full rights could do):
    the guards of ``table`` are removed first, then ``sql`` runs."""
    import sqlalchemy as sa

    engine = sa.create_engine(url)
    try:
        with engine.begin() as conn:
            if conn.dialect.name == "sqlite":
                conn.exec_driver_sql(f"DROP TRIGGER {table}_no_update")
            else:
                from jointdb.store._guards import event_trigger_names

                schema = conn.exec_driver_sql("SELECT current_schema()").scalar()
                for name in event_trigger_names(schema):
                    conn.exec_driver_sql(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
                conn.exec_driver_sql(f"ALTER TABLE {table} DISABLE TRIGGER {table}_immutable")
            conn.exec_driver_sql(sql)
    finally:
        engine.dispose()


def refused_statements(url: str, statements: list[str]) -> list[str]:
    """Run each SQL statement in its own transaction; the ones the database ALLOWED (each refusal must be
    a permission, ownership or immutability error)."""
    import sqlalchemy as sa

    engine = sa.create_engine(url)
    allowed = []
    try:
        for sql in statements:
            try:
                with engine.begin() as conn:
                    conn.exec_driver_sql(sql)
                allowed.append(sql)
            except sa.exc.DBAPIError as exc:
                assert "permission denied" in str(exc) or "must be owner" in str(exc) or "immutable" in str(exc), sql
    finally:
        engine.dispose()
    return allowed


def run_main(capsys, *args):
    """The console entry point (``jointdb.cli.main``) in this process: ``(exit_code, stdout, stderr)``.

    Any exception other than SystemExit propagates (a traceback is a test failure).
    """
    import sys

    from jointdb.cli import main

    capsys.readouterr()
    old = sys.argv
    sys.argv = ["jointdb", *map(str, args)]
    try:
        main()
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    finally:
        sys.argv = old
    out, err = capsys.readouterr()
    return code, out, err


def tree_state(*roots) -> dict[str, str]:
    """Every file under ``roots`` -> SHA-256 of its bytes (SQLite ``-wal``/``-shm`` side files skipped:
    a reader may leave them; their content is compared through :func:`db_rows`)."""
    import hashlib

    state = {}
    for root in map(Path, roots):
        if root.is_file():
            state[str(root)] = hashlib.sha256(root.read_bytes()).hexdigest()
            continue
        if not root.exists():
            continue
        for p in sorted(root.rglob("*")):
            if p.is_file() and not p.name.endswith(("-wal", "-shm")):
                state[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
            elif p.is_dir():
                state[str(p)] = "dir"
    return state


def db_rows(url: str) -> dict[str, list]:
    """All rows of the jointdb tables (as text), read through a fresh connection."""
    import sqlalchemy as sa

    engine = sa.create_engine(url)
    try:
        with engine.connect() as conn:
            tables = set(sa.inspect(conn).get_table_names())
            return {t: sorted(tuple(map(str, r)) for r in conn.execute(sa.text(f"SELECT * FROM {t}")))
                    for t in sorted(tables)}
    finally:
        engine.dispose()


def nested_dict(depth: int) -> dict:
    """``{"a": {"a": ... {}}}``: a JSON object nested ``depth`` levels deep."""
    out: dict = {}
    cur = out
    for _ in range(depth - 1):
        cur["a"] = {}
        cur = cur["a"]
    return out
