"""identify --resample on a log with a huge gap in its time stamps: refused with
the gap's line (it would otherwise allocate gigabytes), and the grid made in
pieces whatever the gaps."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from cli_runner import cli, refused

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


def gapped(path: Path, gap: float, n: int = 1000, step: float = 1e-3) -> Path:
    t = np.concatenate([step * np.arange(n), step * n + gap + step * np.arange(n)])
    rows = np.column_stack([t, 0.1 * np.sin(3 * t), np.cos(2 * t)])
    np.savetxt(path, rows, delimiter=",", header="t,y,u", comments="", fmt="%.17g")
    return path


@pytest.mark.parametrize("gap, resample", [(1e6, []), (1e6, ["0.001"]), (5.0, ["0.001"])])
def test_a_huge_gap_is_refused_with_its_line(tmp_path, gap, resample):
    data = gapped(tmp_path / "gap.csv", gap)
    start = time.monotonic()
    code, text = cli(["identify", str(data), "--out", str(tmp_path / "o"), "--resample",
                      *resample])
    assert code == 2, text
    refused(code, text, f"{data} line 1002", "gap")
    assert time.monotonic() - start < 20
    assert not (tmp_path / "o").exists()


def test_the_grid_is_the_same_made_in_pieces(tmp_path, monkeypatch):
    from harness import recording

    data = gapped(tmp_path / "gap.csv", 0.5)  # 500 missing steps: filled
    options = recording.ReadOptions(resample=0.0)
    whole = recording.read_recording(data, options)
    monkeypatch.setattr(recording, "GRID_PIECE", 7)
    pieces = recording.read_recording(data, options)
    assert 2490 <= len(whole.t) <= 2510
    for a, b in ((whole.t, pieces.t), (whole.y, pieces.y), (whole.u, pieces.u)):
        assert np.array_equal(a, b)
