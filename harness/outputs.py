"""Writing a command's output files: complete or not at all, never over its inputs.

Every command that writes files does so through :class:`Outputs`::

    with Outputs(out, "identify", inputs=[data]) as outputs:
        write_table(outputs.file("estimates.csv"))
        plot(outputs.staging)   # code that picks its own names writes into the folder

Each file is written under a staging folder ``sto-partial-<pid>-<random>`` inside
the output folder and renamed to its name (one atomic rename per file, on the same
file system) only when the whole block has finished.  An exception, Ctrl-C or
SIGTERM, or a full or read-only disk (OSError) inside the block removes the staging
folder: the files of an earlier run stay as they were, none is half-written.  A
staging folder left by a killed process (SIGKILL) is removed by the next command
writing into that folder.  The handler of Ctrl-C and SIGTERM is set before the output
folder is created: a signal while the folder, its lock and the staging folder are made,
or while the block's end renames or removes them, waits until that is done (or undone:
a folder the command created is removed) and then ends the command, so that no signal
can leave a created folder holding only the lock.

Refused with :class:`OutputError` (exit status 2), before anything is written where
the names are known in advance, and again before any rename: an output folder that
is a file; a name that resolves to one of the command's inputs (also through a link,
hard or symbolic); a name that leads out of the output folder through a symbolic
link; a name that is a device, a FIFO or a socket, directly or through a link (a
rename would replace the node itself, for every program on the machine, and writing
through it is no file of the command's: such an output is refused, never written
through); another harness command writing to the same folder (a lock file,
``.sto-harness.lock``, held while the block runs; a single-file output, ``lock=False``,
needs none: its rename is atomic).
"""
from __future__ import annotations

import errno
import os
import shutil
import signal
import stat
import threading
from collections.abc import Callable, Iterable
from pathlib import Path
from types import FrameType, TracebackType

from filelock import FileLock, Timeout

from .names import plain
from .tempdirs import owned_temp_dir, remove_stale

LOCK_NAME = ".sto-harness.lock"


class OutputError(Exception):
    """The output cannot be written as asked; the message names the file or folder."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that cleanup runs as for Ctrl-C."""


def special_file(path: str | os.PathLike) -> str | None:
    """What ``path`` is when it is neither a regular file, a folder nor nothing: "a
    character device", "a block device", "a FIFO" or "a socket" (a link is followed,
    and said); None otherwise (also for a dangling link, which a rename may replace)."""
    path = Path(path)
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):  # nothing there, a dangling link or a name the OS refuses
        return None
    kinds = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
             (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"))
    for test, kind in kinds:
        if test(mode):
            return kind + (" (through a link)" if path.is_symlink() else "")
    if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        return "a special file"
    return None


def shown(*paths: str | os.PathLike) -> str:
    """Paths as a message or the "wrote ..." line shows them: comma-separated, each
    control character (ESC, a carriage return, a newline ...) written as its escape
    (harness.names.plain), so that a file's name cannot move the cursor or recolour the
    terminal."""
    return ", ".join(plain(str(path)) for path in paths)


def refuse_special(path: str | os.PathLike, what: str = "output") -> None:
    """OutputError when the output ``path`` names a device, FIFO or socket, which a
    rename would replace (the node would be gone for every program on the machine)."""
    kind = special_file(path)
    if kind is not None:
        raise OutputError(f"{what} {path} is {kind}, not a file: it is never replaced or "
                          f"written through; choose a file name")


def write_atomically(path: str | os.PathLike, write: Callable[[str], object]) -> Path:
    """``write(name)`` writes the file under a temporary name beside ``path``, renamed
    to ``path`` once it returns (a link at ``path`` is replaced, never followed; a
    device, FIFO or socket at ``path`` is refused with OutputError, before and after
    writing); on an exception nothing is left.  For files written one at a time into
    a folder that a lock already guards (the sweep's)."""
    path = Path(path)
    refuse_special(path)
    partial = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write(str(partial))
        refuse_special(path)  # made while writing: the rename would still replace it
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)
    return path


def _same_file(a: Path, b: Path) -> bool:
    """The same file, by name (links resolved) or by inode (hard links)."""
    try:
        if a.resolve() == b.resolve():
            return True
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except (OSError, RuntimeError):
        return False


class Outputs:
    """A command's output folder for the duration of a ``with`` block (see the module).

    folder: the output folder (created); command: the command's name for messages;
    inputs: the files the command reads (never overwritten); names: the file names
    known in advance (checked on entry, before any computation)."""

    def __init__(self, folder: str | os.PathLike, command: str,
                 inputs: Iterable[str | os.PathLike] = (), names: Iterable[str] = (),
                 lock: bool = True):
        self.folder = Path(folder)
        self.command = command
        self.inputs = [Path(p) for p in inputs]
        self.names = list(names)
        self.lock = lock
        self.staging = Path()  # set on entry
        self.written: list[Path] = []  # the final paths, after a successful block
        self._lock: FileLock | None = None
        self._created = False
        self._holding = False  # a signal now waits (setting up, renaming, cleaning up)
        self._deferred: int | None = None
        self._handlers: dict[int, object] = {}

    # ---- checks -----------------------------------------------------------------------

    def _error(self, text: str) -> OutputError:
        return OutputError(f"harness {self.command}: {text}")

    def check(self, name: str) -> Path:
        """The final path of output ``name`` (relative to the folder), or OutputError if
        it would leave the folder or overwrite an input."""
        relative = Path(name)
        if relative.is_absolute() or ".." in relative.parts or not relative.parts:
            raise self._error(f"output name {name!r} is not a name inside {self.folder}")
        target = self.folder / relative
        try:
            inside, resolved = self.folder.resolve(), target.resolve()
        except (OSError, RuntimeError):  # a loop of symbolic links
            raise self._error(f"{target}: a loop of symbolic links") from None
        if resolved != inside and inside not in resolved.parents:
            raise self._error(f"{target} leads out of {self.folder} through a symbolic link "
                              f"(to {resolved}); remove the link or choose another --out")
        for source in self.inputs:
            if _same_file(target, source):
                raise self._error(f"{target} is the input {source}: writing it would "
                                  f"overwrite the input; choose another --out")
        if target.is_dir() and not target.is_symlink():
            raise self._error(f"{target} is a folder; move it away or choose another --out")
        kind = special_file(target)
        if kind is not None:  # a rename would replace the node itself, for every program
            raise self._error(f"{target} is {kind}, not a file: it is never replaced or "
                              f"written through; choose another --out")
        return target

    # ---- the block --------------------------------------------------------------------

    def __enter__(self) -> Outputs:
        if self.folder.exists() and not self.folder.is_dir():
            kind = special_file(self.folder)
            raise self._error(f"--out {self.folder} exists and is not a folder"
                              + (f" (it is {kind})" if kind else ""))
        for name in self.names:
            self.check(name)  # before the folder is even created
        # The handler first, holding signals: Ctrl-C between the folder's creation and the
        # cleanup's being in place would leave the folder (and its lock) behind.
        self._holding = True
        self._catch_signals()
        try:
            self._make_folder()
            try:
                if self.lock:
                    self._acquire()
                remove_stale(self.folder)  # staging folders of killed commands
                self.staging = owned_temp_dir("partial", base=self.folder)
            except OSError as error:
                raise self._error(f"cannot write to {self.folder}: "
                                  f"{error.strerror or error}") from None
            self._holding = False  # from here a signal interrupts the block at once
            self._raise_deferred()  # one that came while the folder was made
            return self
        except BaseException:
            self._holding = True
            self._undo()
            raise

    def _make_folder(self) -> None:
        """Creates the output folder (and its parents); `_created` says whether this
        command made it (and so removes it again on failure)."""
        try:
            self.folder.mkdir(parents=True)
            self._created = True
        except FileExistsError:
            if not self.folder.is_dir():  # made a file since the check above
                raise self._error(f"--out {self.folder} exists and is not a folder") from None
        except OSError as error:
            raise self._error(f"cannot create --out {self.folder}: "
                              f"{error.strerror or error}") from None

    def _undo(self) -> None:
        """Removes what __enter__ made (the staging folder, the lock, a folder it created)
        and gives the signals back."""
        if self.staging.parts:  # set: Path() until then (never remove the working folder)
            shutil.rmtree(self.staging, ignore_errors=True)
        self._release(failed=True)
        self._restore_signals()

    def _raise_deferred(self) -> None:
        if self._deferred is not None:
            raise Terminated() if self._deferred == signal.SIGTERM else KeyboardInterrupt()

    def file(self, name: str) -> Path:
        """Where to write output ``name`` now (it is renamed to its place at the end)."""
        self.check(name)
        path = self.staging / name
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        self._holding = True  # a signal waits until the outputs are in place or removed
        committed = False
        try:
            if kind is None:
                self._commit()
                committed = True
            elif isinstance(error, OSError) and self._writing(error):
                raise error
        except OSError as problem:
            raise self._error(f"cannot write to {self.folder}: {problem.strerror or problem}; "
                              f"nothing was written") from None
        finally:
            shutil.rmtree(self.staging, ignore_errors=True)
            self._release(failed=not committed)  # a folder made for nothing is removed
            self._restore_signals()
        if not isinstance(error, KeyboardInterrupt):  # that one is on its way already
            self._raise_deferred()  # a signal that came during the renames

    def _writing(self, error: OSError) -> bool:
        """Whether an OSError of the block came from writing (not from reading an input)."""
        if error.errno in (errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG):
            return True
        name = error.filename
        return isinstance(name, (str, os.PathLike)) and Path(self.staging) in Path(name).parents

    def _commit(self) -> None:
        staged = sorted(p for p in self.staging.rglob("*") if p.is_file() or p.is_symlink())
        targets = [self.check(str(p.relative_to(self.staging))) for p in staged]
        self._raise_deferred()  # Ctrl-C before the first rename: nothing is written
        for source, target in zip(staged, targets):  # then it waits for the last one
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(source, target)
            self.written.append(target)

    def final(self, staged: Path) -> Path:
        """The path a file written under :attr:`staging` gets at the end."""
        return self.folder / Path(staged).relative_to(self.staging)

    # ---- the lock -----------------------------------------------------------------------

    def _acquire(self) -> None:
        path = self.folder / LOCK_NAME
        lock = FileLock(str(path), timeout=0, thread_local=False, is_singleton=False)
        try:
            lock.acquire()
        except Timeout:
            raise self._error(f"another harness command is writing to {self.folder} (it "
                              f"holds {path}); wait until it has finished, or choose another "
                              f"--out") from None
        self._lock = lock

    def _release(self, failed: bool) -> None:
        if self._lock is not None:
            self._lock.release()
            self._lock = None
        if failed and self._created:  # a folder this command made and left empty
            try:
                (self.folder / LOCK_NAME).unlink(missing_ok=True)
                self.folder.rmdir()
            except OSError:
                pass

    # ---- signals ------------------------------------------------------------------------

    def _catch_signals(self) -> None:
        if threading.current_thread() is not threading.main_thread():
            return  # only the main thread may set handlers; its caller handles signals
        for number in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(number) is not signal.SIG_IGN:  # nohup: stays ignored
                self._handlers[number] = signal.signal(number, self._on_signal)

    def _restore_signals(self) -> None:
        for number, handler in self._handlers.items():
            signal.signal(number, handler)  # type: ignore[arg-type]
        self._handlers.clear()

    def _on_signal(self, number: int, frame: FrameType | None) -> None:
        # held; or run at __exit__'s first instruction, before it could say so itself
        if self._holding or (frame is not None and frame.f_code is _EXIT_CODE):
            self._deferred = number
            return
        # kept too: raised inside a finalizer (a garbage collection), the exception is
        # printed and dropped by Python and the block goes on; the commit then honours it
        self._deferred = number
        raise Terminated() if number == signal.SIGTERM else KeyboardInterrupt()


_EXIT_CODE = Outputs.__exit__.__code__
