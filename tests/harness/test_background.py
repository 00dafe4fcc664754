"""harness.background: order kept, exceptions raised where the item would have come."""
from __future__ import annotations

import threading

import pytest

from harness.background import WriteBehind, read_ahead


def test_read_ahead_keeps_the_order_and_makes_items_in_another_thread():
    made_in = []

    def items():
        for k in range(5):
            made_in.append(threading.current_thread().name)
            yield k

    assert list(read_ahead(items())) == [0, 1, 2, 3, 4]
    assert all(name.startswith("read-ahead") for name in made_in)


def test_read_ahead_raises_the_error_after_the_items_before_it():
    def items():
        yield 1
        yield 2
        raise ValueError("bad row 3")

    got = []
    with pytest.raises(ValueError, match="bad row 3"):
        for item in read_ahead(items()):
            got.append(item)
    assert got == [1, 2]


def test_write_behind_writes_every_item_in_order():
    written = []
    with WriteBehind(written.append) as writer:
        for k in range(20):
            writer.put(k)
    assert written == list(range(20))


def test_write_behind_raises_a_failed_write_at_the_next_put_or_wait():
    written = []

    def write(item):
        if item == 2:
            raise OSError("disk full")
        written.append(item)

    with pytest.raises(OSError, match="disk full"):
        with WriteBehind(write) as writer:
            for k in range(5):
                writer.put(k)
    assert written == [0, 1]  # nothing after the failed item was written
