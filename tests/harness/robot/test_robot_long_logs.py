"""identify --robot a chunk at a time: the log read in chunks, Lepski's velocity windows
compared a chunk of samples at a time, the friction rows and the Savitzky-Golay signals
at the used samples only, velocities.csv written in chunks give what the whole log at
once gives (tiny chunks on a short log against the whole-log computations)."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest
from robot_helpers import FRICTION, multisine_log, payload_link
from scipy.signal import savgol_coeffs, savgol_filter

from harness import csv_columns
from harness.cli import main
from harness.robot import results, smoothing
from harness.robot.examples import example_urdf
from harness.robot.joint_log import JointLog, read_log
from harness.robot.results import plot_samples
from harness.robot.smoothing import savitzky_golay
from harness.robot.urdf import read_urdf


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


def _write_log(path, robot, seconds: float = 4.0, h: float = 1e-3, bits: int = 17):
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    t, q, _, _, tau = multisine_log(truth, seconds, h)
    resolution = 2 * np.pi / 2 ** bits
    q = np.round(q / resolution) * resolution
    np.savetxt(path, np.column_stack([t, q, tau]), delimiter=",", header="t,q1,q2,u1,u2",
               comments="")
    return path


def _lepski_whole(x: np.ndarray, h: float) -> tuple[np.ndarray, float]:
    """Lepski's rule over the whole log at once, every kept candidate's velocity in
    memory: the rule smoothing.joint_velocity computes a chunk at a time."""
    windows = smoothing.candidate_windows(h, x.size)
    margin = windows[-1] // 2 + 1
    inside = slice(margin, x.size - margin)
    sigma = max(smoothing.noise_std(x), 1e-15 * (1.0 + float(np.max(np.abs(x)))))
    kept: list[tuple[np.ndarray, float]] = []
    chosen = windows[0]
    for length in windows:
        velocity = savgol_filter(x, length, smoothing.ORDER, deriv=1, delta=h)
        if any(np.sqrt(np.mean((velocity[inside] - shorter[inside]) ** 2)) > smoothing.KAPPA * s
               for shorter, s in kept):
            break
        c = savgol_coeffs(length, smoothing.ORDER, deriv=1, delta=h)
        kept.append((velocity, sigma * float(np.sqrt(np.sum(c ** 2)))))
        chosen = length
    return kept[-1][0], chosen * h


@pytest.mark.parametrize("noise", [0.0, 1e-5, 1e-3])
@pytest.mark.parametrize("chunk", [1, 37, 1 << 20])
def test_lepski_a_chunk_at_a_time_is_the_whole_log_rule(noise, chunk):
    h = 1e-3
    t = np.arange(6000) * h
    x = (np.sin(1.3 * t) + 0.3 * np.sin(7.0 * t)
         + noise * np.random.default_rng(2).normal(size=t.size))
    velocity, window = smoothing.joint_velocity(x, h, chunk=chunk)
    whole_velocity, whole_window = _lepski_whole(x, h)
    assert window == whole_window
    assert np.array_equal(velocity, whole_velocity)


def test_lepski_windows_differ_with_the_noise():
    """The comparison above covers both ends of the rule: short and long windows."""
    h = 1e-3
    t = np.arange(6000) * h
    clean = np.sin(1.3 * t) + 0.3 * np.sin(7.0 * t)
    noisy = clean + 1e-3 * np.random.default_rng(2).normal(size=t.size)
    assert smoothing.joint_velocity(clean, h)[1] < 0.5 * smoothing.joint_velocity(noisy, h)[1]


def test_the_log_read_in_tiny_chunks_is_the_log(tmp_path, arm, monkeypatch):
    _, robot = arm
    path = _write_log(tmp_path / "arm.csv", robot, seconds=0.5)
    whole = np.loadtxt(path, delimiter=",", skiprows=1)
    monkeypatch.setattr(csv_columns, "CHUNK_ROWS", 7)
    log = read_log(path, 2)
    assert np.array_equal(np.column_stack([log.t, log.q, log.u]), whole)
    # lines that end in a lone carriage return: more rows than line feeds
    lone = tmp_path / "cr.csv"
    lone.write_bytes(path.read_bytes().replace(b"\n", b"\r"))
    log = read_log(lone, 2)
    assert np.array_equal(np.column_stack([log.t, log.q, log.u]), whole)


def test_savitzky_golay_at_the_used_samples_is_the_whole_logs():
    h = 1e-3
    t = np.arange(3000) * h
    log = JointLog(t, np.column_stack([np.sin(t), np.cos(2 * t)]),
                   np.column_stack([np.sin(3 * t), t]))
    used = np.arange(100, 2900, 13)
    whole = [savgol_filter(x, 51, 4, deriv=d, delta=h, axis=0)
             for x, d in ((log.q, 0), (log.q, 1), (log.q, 2), (log.u, 0))]
    for at, part in zip(savitzky_golay(log, 0.05, at=used), whole):
        assert np.array_equal(at, part[used])  # the same filter away from the ends
    for every, part in zip(savitzky_golay(log, 0.05), whole):
        # the ends: the edge polynomial fitted per column, equal to rounding
        np.testing.assert_allclose(every, part, rtol=1e-10, atol=1e-10 * np.abs(part).max())


def test_plot_samples_keep_each_stretchs_extremes():
    x = np.random.default_rng(1).normal(size=100_003)
    shown = plot_samples(x, bins=100)
    assert shown[0] == 0 and shown[-1] == len(x) - 1 and np.all(np.diff(shown) > 0)
    assert len(shown) <= 2 * 101 + 2
    width = -(-len(x) // 100)
    for start in range(0, len(x), width):
        stretch = x[start:start + width]
        inside = shown[(shown >= start) & (shown < start + width)]
        assert x[inside].min() == stretch.min() and x[inside].max() == stretch.max()
    assert plot_samples(x[:200], bins=100) == slice(None)


def _outputs(out):
    return {name: (out / name).read_bytes()
            for name in ("velocities.csv", "parameters.csv", "summary.json")}


@pytest.mark.parametrize("velocity", ["sg", "observer"])
def test_identify_in_tiny_chunks_writes_what_large_chunks_write(tmp_path, arm, monkeypatch,
                                                                velocity):
    urdf, robot = arm
    data = _write_log(tmp_path / "arm.csv", robot)
    command = ["identify", str(data), "--robot", str(urdf), "--unknown", "payload",
               "--velocity", velocity, "--quiet"]
    for name, value in ((csv_columns, "CHUNK_ROWS"), (smoothing, "CHUNK"),
                        (results, "WRITE_ROWS")):
        monkeypatch.setattr(name, value, 1 << 30)
    assert main([*command, "--out", str(tmp_path / "whole")]) == 0
    monkeypatch.setattr(csv_columns, "CHUNK_ROWS", 11)
    monkeypatch.setattr(smoothing, "CHUNK", 13)
    monkeypatch.setattr(results, "WRITE_ROWS", 17)
    assert main([*command, "--out", str(tmp_path / "chunks")]) == 0
    whole, chunks = _outputs(tmp_path / "whole"), _outputs(tmp_path / "chunks")
    assert chunks["velocities.csv"] == whole["velocities.csv"]
    # the estimate to the last digit; the consistent model to the projection's own
    # precision (its prior-decided directions move by ~1e-9 relative from one process to
    # the next: numpy's sums differ in the last bit with the arrays' alignment)
    a, b = (np.genfromtxt(io.BytesIO(o["parameters.csv"]), delimiter=",", names=True,
                          dtype=None, encoding="utf-8") for o in (whole, chunks))
    assert list(a["estimate"]) == list(b["estimate"])
    np.testing.assert_allclose(b["consistent"], a["consistent"], rtol=1e-6, atol=1e-9)
    summary = json.loads(whole["summary.json"])
    payload = list(summary["masses"].values())[1] - robot.arrays()["link"][1, 0]
    assert abs(payload - 0.3) < 0.03  # the payload
    rows = whole["velocities.csv"].decode().splitlines()
    assert rows[0] == "t,qd1,qd2" and len(rows) == 4001
