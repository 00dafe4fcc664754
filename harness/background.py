"""Work on the next item of a stream in a thread while the caller works on this one.

identify streams a log through three stages (parse a block, run the observer
over it, write its estimates); the C code of each one runs without the GIL,
so on two cores reading and writing overlap the observer's run.  One item at
a time is ahead or behind: memory stays that of a few blocks.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, TypeVar, cast

T = TypeVar("T")
_END = object()


def read_ahead(items: Iterator[T]) -> Iterator[T]:
    """The items in order, each next one made in a thread while the caller has this one;
    an exception of ``items`` is raised where its item would have come."""
    with ThreadPoolExecutor(1, thread_name_prefix="read-ahead") as pool:
        pending = pool.submit(next, items, _END)
        while (item := pending.result()) is not _END:
            pending = pool.submit(next, items, _END)
            yield cast(T, item)


class WriteBehind:
    """Calls ``write`` with each item in a thread, one call at a time and in order; an
    exception of ``write`` is raised by the next call of :meth:`put` or by :meth:`wait`."""

    def __init__(self, write: Callable[[Any], None]):
        self.write = write
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="write-behind")
        self._pending: Future | None = None

    def put(self, item: Any) -> None:
        self.wait()
        self._pending = self._pool.submit(self.write, item)

    def wait(self) -> None:
        """Until the last item is written."""
        if self._pending is not None:
            pending, self._pending = self._pending, None
            pending.result()

    def __enter__(self) -> WriteBehind:
        return self

    def __exit__(self, *exc) -> None:
        try:
            if exc[0] is None:
                self.wait()
        finally:
            self._pool.shutdown(wait=True)
