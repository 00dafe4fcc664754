"""One BLAS thread for the command line, unless the environment chooses."""
from __future__ import annotations

from threadpoolctl import threadpool_info

from harness.blas_threads import THREAD_VARIABLES, one_blas_thread


def _blas_threads() -> list[int]:
    import numpy  # noqa: F401  (loads the BLAS that threadpoolctl reports)
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_the_block_runs_blas_on_one_thread(monkeypatch):
    for name in THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    before = _blas_threads()
    assert before, "numpy's BLAS is not visible to threadpoolctl"
    with one_blas_thread():
        assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before


def test_a_thread_count_the_user_set_stands(monkeypatch):
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")
    before = _blas_threads()
    with one_blas_thread():
        assert _blas_threads() == before
