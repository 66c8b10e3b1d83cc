import pytest


@pytest.fixture(autouse=True)
def _one_blas_thread():
    """Tiny dense problems run much faster on one BLAS thread (see jointdb.diagnose_bench._blas)."""
    from jointdb.diagnose_bench import single_blas_thread

    with single_blas_thread():
        yield
