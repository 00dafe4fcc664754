"""harness.recording: the t, y, u log of identify, read in blocks and checked (columns
by name, a time unit, even steps within the tolerance, or resampled)."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from cli_runner import cli, refused

from harness.recording import (
    DataError,
    ReadOptions,
    parse_columns,
    read_blocks,
    read_recording,
)


def _log(path, t, header="time,theta,tau"):
    rows = "\n".join(f"{s},{np.sin(k)},{np.cos(k)}" for k, s in enumerate(t))
    path.write_text(f"{header}\n{rows}\n")
    return path


def test_columns_are_mapped_by_name_in_any_case(tmp_path):
    path = _log(tmp_path / "log.csv", [f"{k * 0.01:.2f}" for k in range(50)],
                header="Time,THETA,tau")
    options = ReadOptions(columns=parse_columns("y=theta, u=Tau"))
    recording = read_recording(path, options)
    assert recording.step == pytest.approx(0.01)
    np.testing.assert_allclose(recording.y, np.sin(np.arange(50)))


def test_epoch_stamps_keep_their_digits_in_the_time_since_the_first(tmp_path):
    path = _log(tmp_path / "log.csv", [f"1700000000.{k:06d}" for k in range(0, 50000, 1000)])
    blocks = list(read_blocks(path, ReadOptions(columns={"y": "theta", "u": "tau"})))
    time = np.concatenate([b.time for b in blocks])
    assert time[1] == 0.001 and time[-1] == pytest.approx(0.049, abs=1e-15)
    assert blocks[0].stamps[0].as_py() == "1700000000.000000"  # kept as written


def test_uneven_steps_are_refused_or_resampled(tmp_path):
    t = np.arange(200) * 0.01
    t[100:] += 0.005  # a step of 1.5 sampling steps
    path = _log(tmp_path / "log.csv", [repr(float(s)) for s in t])
    options = ReadOptions(columns={"y": "theta", "u": "tau"})
    with pytest.raises(DataError, match=r"line 102: sampling step 0\.015 s differs"):
        read_recording(path, options)
    options.resample = 0.0
    resampled = read_recording(path, options)
    np.testing.assert_allclose(np.diff(resampled.t), 0.01, rtol=1e-9)


@pytest.mark.parametrize("text, said", [("y=theta,v=vel", "ROLE one of t, y, u"),
                                        ("theta", "expected ROLE=NAME")])
def test_bad_column_options_are_named(text, said):
    with pytest.raises(DataError, match=said):
        parse_columns(text)


# ---- identify --resample on a log with a huge gap: refused with the gap's line, and
# the grid made in pieces whatever the gaps ----

def gapped(path: Path, gap: float, n: int = 1000, step: float = 1e-3) -> Path:
    t = np.concatenate([step * np.arange(n), step * n + gap + step * np.arange(n)])
    rows = np.column_stack([t, 0.1 * np.sin(3 * t), np.cos(2 * t)])
    np.savetxt(path, rows, delimiter=",", header="t,y,u", comments="", fmt="%.17g")
    return path


@pytest.mark.cli
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


@pytest.mark.cli
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
