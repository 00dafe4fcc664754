"""MATLAB (v4 to v7) files read in a child process.

scipy's MATLAB reader is C code that trusts the sizes written in the file: a damaged
or forged file can crash it (a segmentation fault), which would take the command down
with it and no message. The file is therefore read by ``python -m harness.mat_file``,
which hands the numeric variables back in an ``.npz`` file (no pickles); a crash of the
child is reported as the file's fault, by name.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

_META = "meta"  # the npz entry with the error and the non-numeric variables
_PREFIX = "v_"  # before each variable's name in the npz


class MatFileError(ValueError):
    """The file is missing, unreadable or not a MATLAB file scipy can read."""


class MatVariables(dict[str, np.ndarray]):
    """The numeric variables of a MATLAB file by name; ``others`` maps the rest (cells,
    structs, strings) to a description of their shape and type."""

    others: dict[str, str]


def load_mat(path: str | Path) -> MatVariables:
    """The variables of the MATLAB file ``path``, read in a child process."""
    path = Path(path)
    with tempfile.TemporaryDirectory(prefix="sto-mat-") as folder:
        out = Path(folder) / "variables.npz"
        # the child finds this package where the parent did (a checkout, an install)
        search = os.pathsep.join(filter(None, [str(Path(__file__).parent.parent),
                                               os.environ.get("PYTHONPATH")]))
        done = subprocess.run([sys.executable, "-m", "harness.mat_file", str(path), str(out)],
                              stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, check=False,
                              env={**os.environ, "PYTHONPATH": search})
        if done.returncode < 0:
            try:
                name = signal.Signals(-done.returncode).name
            except ValueError:
                name = f"signal {-done.returncode}"
            raise MatFileError(f"{path}: not a readable MATLAB file (scipy's reader crashed "
                               f"on it, {name}: the file is damaged or forged)")
        if done.returncode != 0 or not out.is_file():
            said = done.stderr.decode(errors="replace").strip().splitlines()
            raise MatFileError(f"{path}: not a readable MATLAB file (its reader failed: "
                               f"{said[-1] if said else f'exit {done.returncode}'})")
        with np.load(out, allow_pickle=False) as stored:
            meta = json.loads(str(stored[_META]))
            if meta["error"] is not None:
                raise MatFileError(meta["error"])
            variables = MatVariables({k[len(_PREFIX):]: stored[k] for k in stored.files
                                      if k.startswith(_PREFIX)})
    variables.others = meta["others"]
    return variables


def _read(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The numeric variables of ``path`` and a description of the others (in the child)."""
    import scipy.io

    data = scipy.io.loadmat(str(path))
    numeric, others = {}, {}
    for name, value in data.items():
        if name.startswith("__"):
            continue
        value = np.asarray(value)
        if value.dtype.kind in "fiub":
            numeric[name] = value
        else:
            others[name] = f"shape {value.shape}, type {value.dtype}"
    return numeric, others


def _error(path: Path, exc: BaseException) -> str:
    """What is wrong with ``path``, from the exception scipy's reader raised on it."""
    from scipy.io.matlab import MatReadError

    if isinstance(exc, FileNotFoundError):
        return f"{path}: no such file"
    if isinstance(exc, NotImplementedError):  # MATLAB v7.3 files are HDF5
        return f"{path}: a MATLAB v7.3 (HDF5) file; save it with -v7 or as CSV"
    if isinstance(exc, OSError):
        if exc.errno is not None:  # the system's (permissions ...); scipy's own OSError
            return f"{path}: cannot read it ({exc.strerror or exc})"
        return f"{path}: not a readable MATLAB file (it ends too early: {exc})"
    if isinstance(exc, MatReadError):  # empty, or not MATLAB's header
        return f"{path}: not a readable MATLAB file ({exc})"
    # scipy's parser fails on a file that is not MATLAB's (text, truncated, forged) in
    # many ways: IndexError, ValueError, struct.error, zlib.error, MemoryError for a
    # forged size ... each is the file's fault, not a bug to show as a traceback
    return f"{path}: not a readable MATLAB file ({type(exc).__name__}: {exc})"


def _main(source: str, target: str) -> None:
    """The child: read ``source``, write what was found (or the error) to ``target``."""
    path = Path(source)
    try:
        numeric, others = _read(path)
        error = None
    except Exception as exc:  # noqa: BLE001 - every failure is reported as the file's
        numeric, others, error = {}, {}, _error(path, exc)
    meta = np.array(json.dumps({"error": error, "others": others}))
    # prefixed: a variable may be called "file", np.savez's own argument
    arrays: dict[str, Any] = {_PREFIX + k: v for k, v in numeric.items()}
    np.savez(target, allow_pickle=False, **arrays, **{_META: meta})


if __name__ == "__main__":
    _main(sys.argv[1], sys.argv[2])
