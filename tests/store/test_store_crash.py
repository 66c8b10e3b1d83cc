"""A cataloguing process killed with SIGKILL at random points, many times.

After every kill the database must pass ``db check``: no row points at a
missing or corrupt blob, every visible version is complete (record hash
verifies) and numbering has no gaps.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import random
import signal
import subprocess
import sys
import time

import pytest

from jointdb.errors import NotFoundError

ITERATIONS = 20

def _child(url: str, blobs: str, seed: int, ready) -> None:
    """Catalogue versions forever (until SIGKILL)."""
    import numpy as np

    from jointdb.frf import FRF
    from jointdb.store import Conditions, Repository

    repo = Repository(url, blobs=blobs)
    f = np.linspace(1.0, 4000.0, 2000)
    ready.set()
    i = 0
    while True:
        k = 1e6 * (1 + seed) + i
        h = np.zeros((f.size, 2, 2), complex)
        h[:, 0, 0] = 1 / (k + 2j * np.pi * f * 100.0)
        h[:, 1, 1] = 1 / (8e4 + 2j * np.pi * f * (80.0 + i))
        repo.catalogue(f"crash-{i % 3}", "tool-holder", FRF(f, h, ["3x", "3ry"], ["3x", "3ry"]),
                       Conditions(("steel",), torque_nm=10.0 + i, extra={"seed": seed, "i": i}),
                       "spring-damper-planar", raw_frfs={"tip": FRF(f, 2 * h, ["1x", "1ry"], ["1x", "1ry"])}, force=True)
        i += 1


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL")
def test_sigkill_at_random_points_never_leaves_a_broken_database(backend):
    rng = random.Random(20261122)
    ctx = mp.get_context("fork")
    visible_before = 0
    verified: set[str] = set()
    interrupted = 0  # kills that left a new unfinished write behind (blob without row, temp file)
    debris: set[str] = set()
    for it in range(ITERATIONS):
        # a forked process (the modules are already imported, so the kill can land
        # anywhere in catalogue() within the first few hundred milliseconds)
        ready = ctx.Event()
        proc = ctx.Process(target=_child, args=(backend.url, str(backend.blobs), it, ready))
        proc.start()
        assert ready.wait(timeout=60), "child did not start"
        time.sleep(rng.uniform(0.0, 0.6))
        os.kill(proc.pid, signal.SIGKILL)
        proc.join(timeout=30)
        assert proc.exitcode == -signal.SIGKILL, "the child must have been killed, not have stopped"

        repo = backend.repo()
        # every row: record hash, numbering, blob present (blobs are immutable once
        # renamed into place, so only the newly visible ones are read and hashed here;
        # the final CLI check below reads every blob)
        report = repo.check(verify_blobs=False)
        assert report.ok, f"iteration {it}: {report.problems}"
        visible = report.versions_checked
        assert visible >= visible_before  # nothing committed is ever lost
        for j in range(3):
            try:
                hist = repo.history(f"crash-{j}")
            except NotFoundError:  # joint not created yet
                continue
            assert [v.version for v in hist] == list(range(1, len(hist) + 1))
            for v in hist:
                if v.uuid not in verified:
                    for digest in (v.blob_sha256, *v.raw_blobs.values()):
                        assert repo.blobs.verify(digest) is None, f"iteration {it}: {v.name} v{v.version}"
                    verified.add(v.uuid)
        visible_before = visible
        debris_now = set(report.temporaries) | set(report.orphan_blobs)
        interrupted += bool(debris_now - debris)
        debris |= debris_now
        repo.close()
    assert visible_before > 0, "no version was ever committed: the kills came too early to test anything"
    print(f"{ITERATIONS} kills, {visible_before} versions committed, {interrupted} kills left blob debris")
    # the command-line check agrees
    out = subprocess.run(
        [sys.executable, "-m", "jointdb", "db", "check", "--db", backend.url, "--blobs", str(backend.blobs), "--json"],
        capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    assert '"ok": true' in out.stdout
