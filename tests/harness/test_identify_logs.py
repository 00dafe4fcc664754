"""identify on real logs: column names, time units, jitter, resampling, epoch stamps, trust."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from fmpy.util import read_csv

from harness.cli import main
from harness.recording import DataError, ReadOptions, parse_columns, read_recording


def _log(path, t, header=("t", "y", "u"), stamps=None):
    y = 0.1 * np.sin(3 * t) + 0.02 * np.sin(11 * t)
    u = np.cos(2 * t)
    frame = pd.DataFrame({header[0]: t if stamps is None else stamps, header[1]: y,
                          header[2]: u})
    frame.to_csv(path, index=False, float_format="%.17g")
    return path, y, u


def test_fmpys_time_header_and_a_column_mapping_are_read(tmp_path):
    t = np.arange(500) * 1e-3
    path, y, u = _log(tmp_path / "a.csv", t, header=("time", "theta", "tau"))
    with pytest.raises(DataError, match="missing column"):
        read_recording(path)
    recording = read_recording(path, ReadOptions(columns=parse_columns("y=theta,u=tau")))
    np.testing.assert_array_equal(recording.y, y)
    np.testing.assert_array_equal(recording.t, t)
    with pytest.raises(DataError, match="expected ROLE=NAME"):
        parse_columns("x=theta")


def test_millisecond_stamps_warn_and_convert(tmp_path, caplog, observer_fmu):
    t_ms = np.arange(400) * 1.0
    path, *_ = _log(tmp_path / "ms.csv", t_ms)
    assert read_recording(path, ReadOptions(time_unit="ms")).step == pytest.approx(1e-3)
    with caplog.at_level("WARNING", logger="harness"):
        read_recording(path)
    assert "--time-unit ms" in caplog.text
    code = main(["identify", str(path), "--out", str(tmp_path / "o"), "--fmu-dir",
                 str(observer_fmu.parent)])
    assert code == 1  # written, but not to be trusted as seconds
    assert main(["identify", str(path), "--out", str(tmp_path / "o2"), "--time-unit", "ms",
                 "--fmu-dir", str(observer_fmu.parent)]) == 0


def test_jitter_within_the_tolerance_is_accepted_and_larger_is_resampled(tmp_path):
    rng = np.random.default_rng(1)
    t = np.arange(3000) * 1e-3 + rng.uniform(-2e-6, 2e-6, 3000)  # 2 us logger jitter
    path, y, _ = _log(tmp_path / "j.csv", t)
    assert len(read_recording(path).t) == 3000
    with pytest.raises(DataError, match=r"line \d+: sampling step .* --resample"):
        read_recording(path, ReadOptions(tolerance=1e-4))
    gaps = np.delete(np.arange(3000) * 1e-3, [100, 101, 2000])  # lost samples
    path, *_ = _log(tmp_path / "g.csv", gaps)
    with pytest.raises(DataError, match="line 102: sampling step 3 ms|line 102: sampling step"):
        read_recording(path)
    uniform = read_recording(path, ReadOptions(resample=1e-3))
    assert len(uniform.t) == 3000
    np.testing.assert_allclose(np.diff(uniform.t), 1e-3, rtol=1e-9)
    expected = 0.1 * np.sin(3 * uniform.t) + 0.02 * np.sin(11 * uniform.t)
    assert np.max(np.abs(uniform.y - expected)) < 1e-5  # linear interpolation over 3 ms


def test_epoch_stamps_run_relative_and_are_written_as_given(tmp_path, observer_fmu):
    stamps = [f"{1722000000 + k // 1000}.{k % 1000:03d}000123" for k in range(3000)]  # ns
    t = np.arange(3000) * 1e-3
    path, y, _ = _log(tmp_path / "e.csv", t, stamps=stamps)
    out = tmp_path / "o"
    assert main(["identify", str(path), "--out", str(out), "--identifier", "off",
                 "--fmu-dir", str(observer_fmu.parent)]) == 0
    written = pd.read_csv(out / "estimates.csv", dtype={"t": str})
    assert list(written["t"]) == stamps  # every digit, beyond a double's
    np.testing.assert_array_equal(written["y"].to_numpy(), y)
    assert json.loads((out / "estimates.json").read_text())["step"] == pytest.approx(1e-3)


def test_estimates_hold_trust_outputs_and_read_with_pandas_and_fmpy(tmp_path, observer_fmu,
                                                                   capsys):
    t = np.arange(4000) * 1e-3
    path, *_ = _log(tmp_path / "r.csv", t, header=("time", "y", "u"))
    out = tmp_path / "o"
    assert main(["identify", str(path), "--out", str(out), "--fmu-dir",
                 str(observer_fmu.parent)]) == 0
    summary = json.loads((out / "estimates.json").read_text())
    assert summary["trust"]["converged"] is True
    assert summary["trust"]["excitation"] >= 0.0
    assert set(summary["standard_error"]) == set(summary["final"])
    frame = pd.read_csv(out / "estimates.csv")
    assert "theta_hat[1][2]" in frame.columns and "excitation" in frame.columns
    from_fmpy = read_csv(out / "estimates.csv")
    assert list(from_fmpy.dtype.names) == list(frame.columns)
    assert frame["theta_hat[1][1]"].iloc[-1] == pytest.approx(summary["final"]["theta_hat[1,1]"],
                                                             rel=1e-15)
    assert "observer converged: yes" in capsys.readouterr().out


def test_bad_gains_reach_stderr_and_the_exit_status(tmp_path, observer_fmu, capsys):
    t = np.arange(500) * 1e-3
    path, *_ = _log(tmp_path / "r.csv", t)
    bad_gains = ["--param", "alpha1[1]=2", "--param", "alpha2[1]=19", "--param", "f_plus[1]=10",
                 "--fmu-dir", str(observer_fmu.parent)]
    code = main(["identify", str(path), "--out", str(tmp_path / "o"), *bad_gains])
    err = capsys.readouterr().err
    assert code == 1
    assert "alpha1[1] = 2 violates (6)" in err
    code = main(["identify", str(path), "--out", str(tmp_path / "o"), *bad_gains, "--quiet"])
    err = capsys.readouterr().err
    assert code == 1 and "violates" not in err and "cannot be trusted" in err


def test_long_logs_are_decimated_in_the_csv(tmp_path, observer_fmu):
    t = np.arange(20000) * 1e-3
    path, *_ = _log(tmp_path / "r.csv", t)
    out = tmp_path / "o"
    assert main(["identify", str(path), "--out", str(out), "--csv-decimation", "10",
                 "--identifier", "off", "--fmu-dir", str(observer_fmu.parent)]) == 0
    frame = pd.read_csv(out / "estimates.csv")
    assert len(frame) == 2000
    np.testing.assert_array_equal(frame["t"].to_numpy(), t[::10])


def test_a_csv_log_is_identified_without_pandas_or_pint(tmp_path, observer_fmu):
    """pyarrow's to_numpy and pyarrow.array load pandas (50 MB, a third of a second), pint
    a quarter of a second: neither is needed for a log in seconds, decimated or not."""
    path, *_ = _log(tmp_path / "r.csv", np.arange(3000) * 1e-3)
    code = ("import sys; from harness.cli import main; main(sys.argv[1:]); "
            "print('loaded:', *(m for m in ('pandas', 'pint') if m in sys.modules))")
    for decimation in ("1", "7"):
        result = subprocess.run(
            [sys.executable, "-c", code, "identify", str(path), "--out",
             str(tmp_path / decimation), "--csv-decimation", decimation, "--quiet",
             "--fmu-dir", str(observer_fmu.parent)], capture_output=True, text=True)
        assert result.returncode in (0, 1), result.stderr
        assert result.stdout.splitlines()[-1] == "loaded:", result.stdout


def test_estimates_as_parquet(tmp_path, observer_fmu):
    t = np.arange(3000) * 1e-3
    path, y, _ = _log(tmp_path / "r.csv", t)
    out = tmp_path / "o"
    assert main(["identify", str(path), "--out", str(out), "--format", "parquet",
                 "--identifier", "off", "--fmu-dir", str(observer_fmu.parent)]) == 0
    frame = pd.read_parquet(out / "estimates.parquet")
    np.testing.assert_array_equal(frame["y"].to_numpy(), y)
    assert len(frame) == 3000 and "theta_hat[1][1]" in frame.columns
