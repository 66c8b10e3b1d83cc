"""Run small dense linear algebra on one BLAS thread (a context manager).

Diagnosis solves thousands of tiny (≈ 60 × 60) eigen- and linear problems;
multi-threaded OpenBLAS makes those 10–40× *slower* on a loaded machine. The
CLI and the benchmark wrap their work in :func:`single_blas_thread`, which
sets the thread count of every loaded OpenBLAS through its C API and restores
it afterwards (no effect, and no error, if none is found).
"""

from __future__ import annotations

import contextlib
import ctypes

_NAMES = (("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
          ("scipy_openblas_set_num_threads", "scipy_openblas_get_num_threads"),
          ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
          ("openblas_set_num_threads", "openblas_get_num_threads"))


def _libraries():
    paths = set()
    try:
        with open("/proc/self/maps") as fh:
            for line in fh:
                if "openblas" in line.lower() and line.rstrip().endswith(".so") or ".so." in line and "openblas" in line:
                    paths.add(line.split()[-1])
    except OSError:
        return []
    out = []
    for p in sorted(paths):
        try:
            lib = ctypes.CDLL(p)
        except OSError:
            continue
        for setter, getter in _NAMES:
            if hasattr(lib, setter) and hasattr(lib, getter):
                out.append((getattr(lib, setter), getattr(lib, getter)))
                break
    return out


@contextlib.contextmanager
def single_blas_thread():
    """Context manager: one OpenBLAS thread inside, the previous count restored after."""
    libs = _libraries()
    saved = [get() for _, get in libs]
    for set_, _ in libs:
        set_(1)
    try:
        yield
    finally:
        for (set_, _), n in zip(libs, saved):
            set_(n)
