"""The command line sets its own BLAS/OpenMP thread policy (issue 26): one thread unless told
otherwise, before numpy loads, inherited by child processes; a user's explicit variables kept."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from jointdb.cli._threads import THREAD_VARIABLES, apply_thread_policy, requested_threads

# Runs the real entry point (a cheap command), then loads numpy and reports the BLAS pools.
PROBE = """
import sys
sys.argv = ["jointdb"] + sys.argv[1:]
from jointdb.cli import main
try:
    main()
except SystemExit:
    pass
import json, numpy, os, threadpoolctl
blas = [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]
print(json.dumps({"blas": blas, "env": os.environ.get("OPENBLAS_NUM_THREADS")}))
"""


def _probe(args: list[str], **env_extra: str) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES and k != "JOINTDB_BLAS_THREADS"}
    env.update(env_extra)
    out = subprocess.run([sys.executable, "-c", PROBE, *args], env=env, capture_output=True, text=True,
                         timeout=120, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


@pytest.mark.skipif(_cores() < 2, reason="one core: the library default is already one thread")
def test_cli_runs_blas_on_one_thread_with_no_variables_set():
    got = _probe(["--version"])
    assert got["blas"], "numpy reported no BLAS library"
    assert set(got["blas"]) == {1}, got
    assert got["env"] == "1"  # inherited by the processes the command starts (serve's workers)


@pytest.mark.skipif(_cores() < 2, reason="needs two cores to see a second thread")
def test_option_and_variable_choose_the_count():
    assert set(_probe(["--blas-threads", "2", "--version"])["blas"]) == {2}
    assert set(_probe(["--version"], JOINTDB_BLAS_THREADS="2")["blas"]) == {2}


@pytest.mark.skipif(_cores() < 2, reason="needs two cores to see a second thread")
def test_a_users_own_variable_is_kept_unless_the_policy_is_explicit():
    assert set(_probe(["--version"], OPENBLAS_NUM_THREADS="2")["blas"]) == {2}
    assert set(_probe(["--blas-threads=1", "--version"], OPENBLAS_NUM_THREADS="2")["blas"]) == {1}


def test_requested_threads_parses_and_refuses():
    assert requested_threads([], {}) == (1, False)
    assert requested_threads(["--blas-threads", "3", "predict"], {}) == (3, True)
    assert requested_threads(["--blas-threads=0"], {}) == (None, True)
    assert requested_threads(["predict", "--", "--blas-threads", "4"], {}) == (1, False)
    assert requested_threads([], {"JOINTDB_BLAS_THREADS": "2"}) == (2, True)
    with pytest.raises(ValueError, match="whole number"):
        requested_threads(["--blas-threads", "many"], {})
    with pytest.raises(ValueError, match="JOINTDB_BLAS_THREADS"):
        requested_threads([], {"JOINTDB_BLAS_THREADS": "-1"})


def test_apply_sets_only_unset_variables_unless_explicit():
    env = {"OMP_NUM_THREADS": "4"}
    apply_thread_policy(1, False, env)
    assert env["OPENBLAS_NUM_THREADS"] == "1" and env["OMP_NUM_THREADS"] == "4"
    apply_thread_policy(2, True, env)
    assert all(env[name] == "2" for name in THREAD_VARIABLES)
    untouched: dict[str, str] = {}
    apply_thread_policy(None, True, untouched)
    assert untouched == {}


def _blas_pools() -> set[int]:
    from threadpoolctl import threadpool_info
    return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}


def test_a_child_environment_leaves_this_process_pools_alone_and_its_own_limits_them(monkeypatch):
    # A mapping built for a child process once also limited *this* process's BLAS (to 2 threads
    # here): every test after it in the same pytest worker ran its small solves 15-45x slower.
    import numpy  # noqa: F401  (the libraries must be loaded for the run-time path)
    from threadpoolctl import ThreadpoolController
    with ThreadpoolController().limit(limits=1, user_api="blas"):  # restored on exit, whatever happens
        apply_thread_policy(2, True, {})
        assert _blas_pools() == {1}
        for name in THREAD_VARIABLES:
            monkeypatch.setenv(name, "1")  # monkeypatch restores the process environment
        apply_thread_policy(2, True)
        assert _blas_pools() == {2}
    assert _blas_pools() == {1}


def test_bad_thread_count_is_one_line_exit_2():
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    out = subprocess.run([sys.executable, "-m", "jointdb", "--blas-threads", "x", "--version"], env=env,
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2
    assert out.stderr.startswith("error: --blas-threads") and out.stderr.count("\n") == 1
