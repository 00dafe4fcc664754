"""Offline identification from recorded data: clear errors, and it identifies."""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.cli import main
from harness.identify import DataError, identify, read_recording


def _write(path, text):
    path.write_text(text)
    return path


@pytest.mark.parametrize("text, message", [
    ("t,y\n0,0\n", r"line 1: missing column\(s\) u"),
    ("t,y,u\n0,0,0\n0.001,0,0\n0.002,abc,0\n", r"line 4: y = 'abc' is not a number"),
    ("t,y,u\n0,0,0\n0.001,nan,0\n0.002,0,0\n", r"line 3: y = nan is not finite"),
    ("t,y,u\n0,0,0\n0.001,0,0\n0.0025,0,0\n0.0035,0,0\n", r"line 4: sampling step"),
    ("t,y,u\n0,0,0\n0.001,0\n0.002,0,0\n", r"line 3: column 'u' is missing"),
    ("t,y,u\n0,0,0\n", r"1 data row\(s\); at least 3"),
    ("", r"the file is empty"),
    ("t,y,u\n1,0,0\n0,0,0\n-1,0,0\n", r"line 3: time does not increase"),
])
def test_bad_recordings_get_a_message_that_names_the_line(tmp_path, text, message):
    with pytest.raises(DataError, match=message):
        read_recording(_write(tmp_path / "data.csv", text))


def test_cli_reports_data_errors_without_traceback(tmp_path, capsys, observer_fmu):
    data = _write(tmp_path / "data.csv", "t,y,u\n0,0,0\n0.001,inf,0\n0.002,0,0\n")
    code = main(["--fmu-dir", str(observer_fmu.parent), "identify", str(data), "--out",
                 str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert "line 3: y = inf is not finite" in err
    assert "Traceback" not in err


def _pendulum_recording(seconds=12.0, dt=1e-3):
    """A pendulum with friction driven by a rich torque, integrated finely (RK4, dt/20)."""
    J = 0.891
    c = [1.1 * 9.815 * 0.9 / (2 * J), 0.18 / J, 0.45 / J]

    def accel(x1, x2, u):
        return u / J - c[0] * math.sin(x1) - c[1] * x2 - c[2] * np.sign(x2)

    n, sub = int(seconds / dt), max(2, int(round(20e-3 / dt / 1000)))
    hh = dt / sub
    t = np.arange(n + 1) * dt
    u = 3 * np.sin(2 * t) + 2 * np.sin(5.3 * t)
    y = np.empty(n + 1)
    x1 = x2 = 0.0
    for k in range(n + 1):
        y[k] = x1
        for _ in range(sub):
            k1 = (x2, accel(x1, x2, u[k]))
            k2 = (x2 + hh / 2 * k1[1], accel(x1 + hh / 2 * k1[0], x2 + hh / 2 * k1[1], u[k]))
            k3 = (x2 + hh / 2 * k2[1], accel(x1 + hh / 2 * k2[0], x2 + hh / 2 * k2[1], u[k]))
            k4 = (x2 + hh * k3[1], accel(x1 + hh * k3[0], x2 + hh * k3[1], u[k]))
            x1 += hh / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            x2 += hh / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    return t, y, u, c


def test_identify_recovers_the_coefficients_from_1khz_data(tmp_path, observer_fmu):
    t, y, u, c = _pendulum_recording()
    data = tmp_path / "rec.csv"
    np.savetxt(data, np.column_stack([t, y, u]), delimiter=",", header="t,y,u", comments="")
    recording = read_recording(data)
    assert recording.step == pytest.approx(1e-3)
    columns = identify(recording, observer_fmu, {
        "b": 1 / 0.891, "c_nominal[1]": 2.0, "c_nominal[2]": 0.1, "c_nominal[3]": 0.1,
        "alpha1[1]": 12.0, "alpha2[1]": 30.0, "identifier": 1})
    # measured: 2e-4, 4.8e-3, 3.0e-3
    for k, tolerance in zip((1, 2, 3), (1e-3, 0.02, 0.02)):
        assert columns[f"theta_hat[1,{k}]"][-1] == pytest.approx(c[k - 1], rel=tolerance)


def test_cli_writes_estimates_with_standard_errors_and_the_noise_level(tmp_path, capsys,
                                                                       observer_fmu):
    import json

    t, y, u, c = _pendulum_recording(seconds=8.0)
    y = y + np.random.default_rng(3).normal(0.0, 1e-4, y.size)
    data = tmp_path / "rec.csv"
    np.savetxt(data, np.column_stack([t, y, u]), delimiter=",", header="t,y,u", comments="")
    code = main(["--fmu-dir", str(observer_fmu.parent), "identify", str(data), "--out",
                 str(tmp_path / "out"), "--param", "b=1.01", "--param", "c_nominal[1]=2",
                 "--param", "c_nominal[2]=0.1", "--param", "c_nominal[3]=0.1"])
    assert code == 0
    summary = json.loads((tmp_path / "out" / "estimates.json").read_text())
    assert summary["noise_std"] == pytest.approx(1e-4, rel=0.15)
    assert summary["final"]["b_hat"] == pytest.approx(1 / 0.891, rel=0.01)
    for name in ("theta_hat[1,1]", "theta_hat[1,2]", "theta_hat[1,3]", "b_hat"):
        assert 0.0 < summary["standard_error"][name] < 0.05
    assert summary["standard_error"]["theta_hat[1,4]"] == 0.0  # not identified
    assert "+-" in capsys.readouterr().out
    assert (tmp_path / "out" / "identification.png").stat().st_size > 10000


def test_a_sampled_input_becomes_its_interval_means():
    from harness.identify import held_input

    u = np.array([0.0, 2.0, 4.0, 8.0])
    assert held_input(u, "zoh") is u
    np.testing.assert_array_equal(held_input(u, "sampled"), [1.0, 3.0, 6.0, 8.0])
    with pytest.raises(ValueError, match="input_hold = 'linear': expected one of zoh, sampled"):
        held_input(u, "linear")
