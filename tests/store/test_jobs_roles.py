"""The job queue under least privilege (issue 21): `db upgrade --app-role` as the owner applies the
queue's schema (procrastinate's and jointdb_jobs) and grants the application role what the service
and the workers need — queueing, running and finishing a job — and no DDL on those tables."""

from __future__ import annotations

import pytest
import sqlalchemy as sa

pytest.importorskip("procrastinate")

from test_store_roles import two_roles  # noqa: E402,F401 - the two-role schema fixture


def test_the_app_role_queues_and_runs_jobs_but_cannot_drop_the_queue(two_roles):  # noqa: F811
    from jointdb.jobs._execute import execute
    from jointdb.jobs._pg import ProcrastinateQueue
    from jointdb.store import Repository

    repo = Repository(two_roles.app_url, blobs=two_roles.blobs, auto_create=False)
    try:
        q = ProcrastinateQueue(repo)
        q.start()  # the schema is there: the app role creates nothing
        job_id = q.submit("lobes", "alice", {"frf": None})
        with repo.write_engine.connect() as conn:
            n = conn.execute(sa.text("SELECT count(*) FROM procrastinate_jobs WHERE args->>'job_id' = :j"),
                             {"j": job_id}).scalar()
        assert n == 1
        assert execute(q.rows, job_id, repo) == "failed"  # the app role updates the row to its end
        row = q.get(job_id)._mapping
        assert row["state"] == "failed" and row["error"].startswith("frf:")
        q.stop()
        for ddl in ("DROP TABLE jointdb_jobs", "DROP TABLE procrastinate_jobs", "ALTER TABLE jointdb_jobs ADD x int"):
            with pytest.raises(sa.exc.ProgrammingError, match="must be owner|permission denied"):
                with repo.write_engine.begin() as conn:
                    conn.exec_driver_sql(ddl)
    finally:
        repo.close()
