"""Temporary folders that a later process can tell are left over.

Each FMU instance extracts its FMU into a temporary folder and removes it
when closed; a process killed with SIGKILL (an interrupted sweep, a worker
killed by its nanny) cannot.  The folders are therefore named
``sto-<kind>-<pid>-<random>`` after the process that made them, and
:func:`remove_stale` (run at the start of every sweep and on every sweep
worker) removes those whose process is gone.
"""
from __future__ import annotations

import os
import re
import shutil
import tempfile
from pathlib import Path

_NAME = re.compile(r"^sto-([a-z]+)-(\d+)-[A-Za-z0-9_]+$")


def owned_temp_dir(kind: str, base: str | os.PathLike | None = None) -> Path:
    """A new folder sto-<kind>-<pid>-<random> in ``base`` (default: the temp folder)."""
    if not kind.isalpha() or not kind.islower():
        raise ValueError(f"kind {kind!r}: lowercase letters only")
    return Path(tempfile.mkdtemp(prefix=f"sto-{kind}-{os.getpid()}-", dir=base))


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    return True


def remove_stale(base: str | os.PathLike | None = None) -> list[Path]:
    """Removes the sto-<kind>-<pid>-* folders in ``base`` (default: the temp
    folder) whose process no longer runs; returns what it removed.  A folder of
    a live process is kept (a reused pid only delays its removal)."""
    removed: list[Path] = []
    directory = Path(base) if base is not None else Path(tempfile.gettempdir())
    try:
        entries = list(directory.iterdir())
    except OSError:
        return removed
    for entry in entries:
        match = _NAME.match(entry.name)
        if not match or not entry.is_dir() or entry.is_symlink():
            continue
        if _alive(int(match.group(2))):
            continue
        shutil.rmtree(entry, ignore_errors=True)
        if not entry.exists():
            removed.append(entry)
    return removed
