"""The command line's BLAS threads: one, unless the user's environment says otherwise.

The matrices of identification are narrow (at most a few hundred columns), where a
threaded BLAS gains little on an idle machine and loses much on a busy one: its threads
spin waiting for each other while other processes hold the cores. On the 2-core machine of
docs/design/performance.md at a load of 2, a pivoted QR of 2400 x 96 took 0.197 s with
OpenBLAS's two threads against 0.0105 s with one, and `identify --robot --joint-terms auto`
on 3000 UR5 samples 14.5-15.1 s against 6.8-7.3 s.
"""
from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

#: The variables by which a user chooses the BLAS threads (honoured when any is set).
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Within the block, BLAS and LAPACK run on one thread, unless one of
    THREAD_VARIABLES is set in the environment (then its choice stands)."""
    if any(os.environ.get(name) for name in THREAD_VARIABLES):
        yield
        return
    from threadpoolctl import threadpool_limits
    with threadpool_limits(limits=1, user_api="blas"):
        yield
