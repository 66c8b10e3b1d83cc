"""The BLAS / OpenMP thread policy of the ``jointdb`` command line and its service.

jointdb's linear algebra is batched over many small matrices (frequency lines,
candidates, interface DOFs). On such work a multi-threaded BLAS spends more time
waking and synchronising threads than computing: on the 2-core reference machine
``jointdb predict`` on the demo stack took 44 s with OpenBLAS at its default
thread count and 12 s with one thread (issue 26). So jointdb sets the policy
itself instead of relying on the user's environment:

* ``JOINTDB_BLAS_THREADS`` (or the root option ``--blas-threads N``) chooses the
  number of BLAS/OpenMP threads; default 1. ``0`` leaves the libraries at their
  own defaults.
* The thread variables (``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS``,
  ``MKL_NUM_THREADS``, ``BLIS_NUM_THREADS``) are set *before* numpy is imported,
  so every library honours them from its first call, and they are inherited by
  the service's worker processes (``jointdb serve --workers N``).
* A variable the user has set explicitly is left alone unless
  ``--blas-threads``/``JOINTDB_BLAS_THREADS`` is given, which wins.
* If numpy was already imported (jointdb used in-process by another program),
  :func:`apply_thread_policy` limits the loaded libraries at run time with
  threadpoolctl instead.
"""

from __future__ import annotations

import os
import sys

#: Variables read by OpenBLAS, OpenMP, MKL and BLIS at load time.
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")

#: The environment variable that sets the policy (the root option ``--blas-threads`` overrides it).
POLICY_VARIABLE = "JOINTDB_BLAS_THREADS"

#: Threads when nothing is said: one, the fastest for jointdb's small batched matrices.
DEFAULT_THREADS = 1


def requested_threads(argv: list[str], environ: dict[str, str] | None = None) -> tuple[int | None, bool]:
    """The thread count asked for and whether it was asked for explicitly.

    Parameters
    ----------
    argv
        The command-line words (``sys.argv[1:]``); ``--blas-threads N`` or
        ``--blas-threads=N`` anywhere before ``--`` counts.
    environ
        The environment (default ``os.environ``); ``JOINTDB_BLAS_THREADS``.

    Returns
    -------
    (threads, explicit)
        ``threads`` is ``None`` for "leave the libraries at their defaults" (a request of 0),
        else a positive count; ``explicit`` is True when the option or the variable was given.

    Raises
    ------
    ValueError
        The value is not a whole number ≥ 0.
    """
    env = os.environ if environ is None else environ
    value: str | None = None
    upto = argv.index("--") if "--" in argv else len(argv)
    for i, word in enumerate(argv[:upto]):
        if word == "--blas-threads" and i + 1 < upto:
            value = argv[i + 1]
        elif word.startswith("--blas-threads="):
            value = word.split("=", 1)[1]
    source = "--blas-threads"
    if value is None and env.get(POLICY_VARIABLE, "").strip():
        value, source = env[POLICY_VARIABLE].strip(), POLICY_VARIABLE
    if value is None:
        return DEFAULT_THREADS, False
    try:
        n = int(value)
    except ValueError:
        n = -1
    if n < 0:
        raise ValueError(f"{source}: the number of BLAS threads must be a whole number >= 0 (0: the library "
                         f"default), got {value!r}")
    return (n or None), True


def apply_thread_policy(threads: int | None, explicit: bool, environ: dict[str, str] | None = None) -> None:
    """Set the BLAS/OpenMP thread count for this process and the processes it starts.

    Parameters
    ----------
    threads
        Threads per library; ``None`` leaves the libraries at their defaults.
    explicit
        The count was asked for (option or ``JOINTDB_BLAS_THREADS``): it overrides
        thread variables already in the environment. Otherwise a variable the user
        set is kept.
    environ
        The environment to change (default ``os.environ``). Only when it is this
        process's own environment are the already loaded libraries limited too: a
        mapping built for a child process leaves this process's thread pools alone.
    """
    env = os.environ if environ is None else environ
    if threads is None:
        return
    for name in THREAD_VARIABLES:
        if explicit or not env.get(name, "").strip():
            env[name] = str(threads)
    if env is os.environ and "numpy" in sys.modules:  # too late for the variables: limit the loaded libraries
        try:
            from threadpoolctl import threadpool_limits
        except ImportError:  # pragma: no cover - threadpoolctl is a dependency
            return
        threadpool_limits(limits=threads)
