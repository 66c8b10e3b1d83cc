"""Issue 20, item 5 through the API: a contradicting v2 is refused (409, both values named) unless
``"force": true`` (then audited); an identical upload is 200 with the existing version, also when
sent concurrently; ``Idempotency-Key`` makes a retry return the same answer and never a second
version (a reused key with another body is refused); and with client retries across a SIGKILL
of the server nothing is lost and nothing duplicated."""

from __future__ import annotations

import concurrent.futures as cf
import uuid

import pytest
from server_helpers import joint_upload, make_tokens, migrated_database

API = "/api/v1"


def _upload(tmp_path, name, torque=80.0, k=2e6, **extra):
    return joint_upload(tmp_path, name, torque=torque, k=k, **extra)


def test_contradicting_v2_is_refused_and_force_is_audited(server, tmp_path):
    name = f"th-er32-{uuid.uuid4().hex[:6]}"
    with server.client("writer") as c:
        assert c.post(f"{API}/catalogue", json=_upload(tmp_path, name, 80.0)).status_code == 201
        r = c.post(f"{API}/catalogue", json=_upload(tmp_path, name, 30.0, k=9e5))
        assert r.status_code == 409 and "torque_nm 80 (v1) -> 30" in r.json()["error"], r.text
        assert len(c.get(f"{API}/joints/{name}/history").json()["items"]) == 1
        r = c.post(f"{API}/catalogue", json=_upload(tmp_path, name, 30.0, k=9e5, force=True))
        assert r.status_code == 201 and r.json()["version"] == 2, r.text
        audit = c.get(f"{API}/audit", params={"joint": name, "limit": 1}).json()["items"][0]
        assert {"condition": "torque_nm", "from": 80.0, "to": 30.0, "of_version": 1} in audit["details"]["forced"]


def test_identical_upload_twice_is_one_version(server, tmp_path):
    name = f"same-{uuid.uuid4().hex[:6]}"
    body = _upload(tmp_path, name)
    with server.client("writer") as c:
        first = c.post(f"{API}/catalogue", json=body)
        again = c.post(f"{API}/catalogue", json=body)
        assert first.status_code == 201 and first.json()["identical"] is False, first.text
        assert again.status_code == 200 and again.json()["identical"] is True, again.text
        assert again.json()["uuid"] == first.json()["uuid"]
        assert len(c.get(f"{API}/joints/{name}/history").json()["items"]) == 1


def test_concurrent_identical_requests_make_one_version(server, tmp_path):
    name = f"race-{uuid.uuid4().hex[:6]}"
    body = _upload(tmp_path, name)

    def post(_):
        with server.client("writer") as c:
            return c.post(f"{API}/catalogue", json=body)

    with cf.ThreadPoolExecutor(8) as pool:
        answers = list(pool.map(post, range(8)))
    assert sorted(r.status_code for r in answers) == [200] * 7 + [201], [r.text for r in answers]
    assert len({r.json()["uuid"] for r in answers}) == 1
    with server.client("reader") as c:
        assert len(c.get(f"{API}/joints/{name}/history").json()["items"]) == 1


def test_idempotency_key_retry_returns_the_same_answer_and_a_reused_key_is_refused(server, tmp_path):
    name = f"idem-{uuid.uuid4().hex[:6]}"
    body = _upload(tmp_path, name, allow_identical=True)  # only the key can tell a retry from a new request
    key = {"Idempotency-Key": uuid.uuid4().hex}
    with server.client("writer") as c:
        first = c.post(f"{API}/catalogue", json=body, headers=key)
        retry = c.post(f"{API}/catalogue", json=body, headers=key)
        assert first.status_code == retry.status_code == 201, (first.text, retry.text)
        assert retry.json() == first.json()
        assert len(c.get(f"{API}/joints/{name}/history").json()["items"]) == 1
        other = c.post(f"{API}/catalogue", json=_upload(tmp_path, name, k=3e6), headers=key)
        assert other.status_code == 422 and "already used for another request" in other.json()["error"], other.text
        assert c.post(f"{API}/catalogue", json=body).json()["version"] == 2  # no key: allow_identical adds one
    with server.client("admin") as c:  # keys are per token owner: the same key is another owner's new key
        mine = c.post(f"{API}/catalogue", json=_upload(tmp_path, f"{name}-admin"), headers=key)
        assert mine.status_code == 201 and mine.json()["name"] == f"{name}-admin", mine.text


# ----------------------------------------------------------------- retries across a killed server
@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_retries_across_a_sigkill_lose_nothing_and_duplicate_nothing(backend, tmp_path, load_script):
    run_killed_server = load_script("bench/bench_reliability.py").run_killed_server

    with migrated_database(backend, tmp_path) as db:
        token = make_tokens(db, tmp_path / "blobs")["writer"]
        out = run_killed_server(db, tmp_path / "blobs", tmp_path / "server.log", token, clients=4, requests=10,
                                kill_after=12)
    assert out["killed"] and out["lost"] == 0 and out["duplicated"] == 0 and out["db_check_ok"], out
    assert out["succeeded"] == 40 and out["versions"] == 40, out
