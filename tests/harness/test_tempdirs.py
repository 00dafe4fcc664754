"""harness.tempdirs: the temporary folders a command owns, and the sweep of those that
killed commands left (never another program's, never a live command's)."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from harness.tempdirs import owned_temp_dir, remove_stale


def test_only_folders_of_dead_processes_are_removed(tmp_path):
    mine = owned_temp_dir("partial", base=tmp_path)
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    left = tmp_path / f"sto-partial-{dead}-abc123"
    left.mkdir()
    (left / "half.csv").write_text("1,2\n")
    foreign = tmp_path / f"other-{dead}-abc"  # not a name this package makes
    foreign.mkdir()
    assert mine.name.startswith(f"sto-partial-{os.getpid()}-")
    assert remove_stale(tmp_path) == [left]
    assert mine.is_dir() and foreign.is_dir() and not left.exists()


def test_a_link_named_like_a_stale_folder_is_not_followed(tmp_path):
    target = tmp_path / "keep"
    target.mkdir()
    (target / "data").write_text("x")
    (tmp_path / "sto-partial-999999999-abc").symlink_to(target)
    assert remove_stale(tmp_path) == []
    assert (target / "data").exists()


@pytest.mark.parametrize("kind", ["Partial", "a-b", ""])
def test_kinds_are_lowercase_words(tmp_path, kind):
    with pytest.raises(ValueError, match="lowercase letters only"):
        owned_temp_dir(kind, base=tmp_path)
