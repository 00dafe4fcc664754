"""harness.outputs: files appear together when the block ends, or not at all."""
from __future__ import annotations

import gc
import os
import signal
import sys

import pytest

from harness import outputs
from harness.outputs import OutputError, Outputs


def test_files_appear_only_when_the_block_ends(tmp_path):
    out = tmp_path / "out"
    with Outputs(out, "test", names=["a.txt"]) as written:
        written.file("a.txt").write_text("a")
        written.file("sub/b.txt").write_text("b")
        assert not (out / "a.txt").exists()
    assert (out / "a.txt").read_text() == "a" and (out / "sub" / "b.txt").read_text() == "b"
    assert sorted(p.name for p in out.iterdir()) == [".sto-harness.lock", "a.txt", "sub"]


def test_an_exception_leaves_the_earlier_files(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.txt").write_text("earlier")
    with pytest.raises(RuntimeError):
        with Outputs(out, "test") as written:
            written.file("a.txt").write_text("half")
            raise RuntimeError("stop")
    assert sorted(p.name for p in out.iterdir()) == [".sto-harness.lock", "a.txt"]
    assert (out / "a.txt").read_text() == "earlier"


def test_a_folder_made_for_a_failed_block_is_removed(tmp_path):
    with pytest.raises(RuntimeError):
        with Outputs(tmp_path / "new", "test"):
            raise RuntimeError("stop")
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("name", ["../x", "/etc/x", ""])
def test_names_outside_the_folder_are_refused(tmp_path, name):
    with pytest.raises(OutputError, match="not a name inside"):
        with Outputs(tmp_path, "test") as written:
            written.file(name)


def test_a_signal_during_the_renames_waits_until_all_are_done(tmp_path, monkeypatch):
    real = os.replace
    calls = []

    def replace(source, target):
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)
        calls.append(target)
        real(source, target)

    monkeypatch.setattr(outputs.os, "replace", replace)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        with Outputs(out, "test") as written:
            for name in ("a", "b", "c"):
                written.file(name).write_text(name)
    assert len(calls) == 3 and all((out / n).read_text() == n for n in "abc")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_signal_dropped_by_a_finalizer_stops_the_commit(tmp_path):
    """Ctrl-C raised inside a finalizer is printed and dropped by Python and the block
    goes on to its end: the outputs are then not written, the interrupt raised."""
    class Finalized:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGINT)  # its handler raises here, and is dropped

    out = tmp_path / "out"
    out.mkdir()
    (out / "a").write_text("earlier")
    dropped = []
    hook, sys.unraisablehook = sys.unraisablehook, lambda u: dropped.append(u.exc_type)
    try:
        with pytest.raises(KeyboardInterrupt):
            with Outputs(out, "test") as written:
                written.file("a").write_text("new")
                Finalized()
                gc.collect()
    finally:
        sys.unraisablehook = hook
    assert dropped == [KeyboardInterrupt]
    assert (out / "a").read_text() == "earlier"
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
