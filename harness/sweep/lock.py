"""One writer per sweep output folder.

Two ``harness sweep`` processes writing to the same --out would each rewrite
the results table from their own copy and lose the other's rows.  A sweep holds an
exclusive lock on DIR/.sweep.lock (filelock: an OS file lock, released by the
kernel when the process ends, so a killed sweep never leaves a stale lock)
while it reads and writes DIR; a second sweep into DIR is refused at once with
a message instead of waiting.
"""
from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from filelock import FileLock, Timeout

from ..outputs import LOCK_NAME as COMMAND_LOCK

LOCK_NAME = ".sweep.lock"


class OutputLocked(RuntimeError):
    """Another sweep is writing to the output folder."""


@contextmanager
def locked_output(out: Path) -> Iterator[Path]:
    """Holds the lock of output folder ``out`` (created if needed) for the
    duration of the block; OutputLocked at once if another process holds it.
    Also the lock every other harness command takes (harness.outputs), so that no
    identify or reproduce writes into the folder while the sweep does."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / LOCK_NAME
    held: list[FileLock] = []
    try:
        for name, who in ((LOCK_NAME, "another sweep"), (COMMAND_LOCK, "another harness command")):
            lock = FileLock(str(out / name), timeout=0, thread_local=False, is_singleton=False)
            try:
                lock.acquire()
            except Timeout:
                raise OutputLocked(f"{who} is writing to {out} (it holds {out / name}); wait "
                                   f"until it has finished, or sweep into another --out") from None
            held.append(lock)
        yield path
    finally:
        for lock in reversed(held):
            lock.release()
