"""A robot log in other units and formats identifies and validates as the same log in
s, rad and N.m as CSV: time in ms, angles in deg, prismatic positions in mm, torque
columns holding drive currents with --torque-gains, Parquet files and MATLAB files
without a time vector (--sample-rate)."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pandas as pd
import pytest
from robot_helpers import FRICTION, multisine_log, payload_link, random_chain_urdf

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.joint_log import read_log
from harness.robot.log_units import log_units
from harness.robot.pipeline import identify_robot
from harness.robot.urdf import read_urdf

GAINS = (0.37, 2.5)  # N.m/A of the two drives


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    return path, read_urdf(path)


@pytest.fixture(scope="module")
def signals(arm):
    """(t [s], q [rad], tau [N.m]) of the arm with a payload and friction, 8 s at 1 kHz."""
    _, robot = arm
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    t, q, _, _, tau = multisine_log(truth, 8.0, 1e-3)
    return t, q, tau


def _write(path, t, q, u):
    frame = pd.DataFrame({"t": t, "q1": q[:, 0], "q2": q[:, 1], "u1": u[:, 0], "u2": u[:, 1]})
    if path.suffix == ".parquet":
        frame.to_parquet(path)
    else:
        frame.to_csv(path, index=False, float_format="%.17g")
    return path


def _write_mat(path, q, u):
    """A MATLAB file of the joints' vectors, without a time vector."""
    import scipy.io
    scipy.io.savemat(path, {"q1": q[:, 0], "q2": q[:, 1], "u1": u[:, 0], "u2": u[:, 1]})
    return path


def _estimates(folder) -> np.ndarray:
    """The identified base parameters (parameters.csv's estimates, 10 digits)."""
    with (folder / "parameters.csv").open() as handle:
        return np.array([float(row["estimate"]) for row in csv.DictReader(handle)])


def _same(found: np.ndarray, reference: np.ndarray) -> bool:
    """Equal to 1e-9 relative to the largest base parameter (some are near 0)."""
    return bool(np.allclose(found, reference, rtol=0, atol=1e-9 * np.abs(reference).max()))


def _identify(tmp_path, arm, data, name, *options) -> np.ndarray:
    urdf, _ = arm
    out = tmp_path / name
    code = main(["identify", str(data), "--robot", str(urdf), "--out", str(out), *options])
    warnings = json.loads((out / "summary.json").read_text())["warnings"]
    assert code == (1 if warnings else 0), (code, warnings)  # docs/cli.md
    return _estimates(out)


def test_other_units_currents_and_parquet_identify_the_same_parameters(tmp_path, arm, signals):
    t, q, tau = signals
    reference = _identify(tmp_path, arm, _write(tmp_path / "si.csv", t, q, tau), "si")
    assert reference.size == 10 and np.all(np.isfinite(reference))
    assert np.allclose(reference[-4:], FRICTION.ravel(), rtol=1e-4)  # measured: 2.7e-6
    cases = {
        "deg_ms": (_write(tmp_path / "deg_ms.csv", 1e3 * t, np.degrees(q), tau),
                   ["--time-unit", "ms", "--angle-unit", "deg"]),
        "currents": (_write(tmp_path / "amps.csv", t, q, tau / np.array(GAINS)),
                     ["--torque-gains", ",".join(map(repr, GAINS))]),
        # a drive mounted the other way round: its current has the torque's opposite sign
        "signed": (_write(tmp_path / "signed.csv", t, q, tau / np.array([GAINS[0], -GAINS[1]])),
                   ["--torque-gains", f"{GAINS[0]!r},{-GAINS[1]!r}"]),
        "parquet": (_write(tmp_path / "si.parquet", t, q, tau), []),
        "all": (_write(tmp_path / "all.parquet", 1e3 * t, np.degrees(q), tau / np.array(GAINS)),
                ["--time-unit", "ms", "--angle-unit", "deg", "--torque-gains", "0.37,2.5"]),
        "mat": (_write_mat(tmp_path / "log.mat", q, tau), ["--sample-rate", "1000"]),
    }
    for name, (data, options) in cases.items():
        found = _identify(tmp_path, arm, data, name, *options)
        assert _same(found, reference), (name, found - reference)
    # the same numbers as Parquet and as CSV: identical, not merely close
    assert np.array_equal(_estimates(tmp_path / "parquet"), reference)
    # and the units were applied: read in the wrong units, the log gives other values
    wrong = _identify(tmp_path, arm, cases["currents"][0], "wrong")
    assert np.max(np.abs(wrong - reference) / np.abs(reference)) > 0.5


def test_a_log_in_ms_and_deg_gives_the_parameters_to_full_precision(tmp_path, arm, signals):
    """The least-squares estimates at full precision (not parameters.csv's 10 digits): a
    step of 1 ms read from milliseconds is 1e-3 within a rounding, which must not move a
    sample of the regression (it moved the first one, by 1e-9 of the estimates)."""
    _, robot = arm
    t, q, tau = signals
    reference = identify_robot(robot, read_log(_write(tmp_path / "si.csv", t, q, tau), 2))
    units = log_units(["revolute", "revolute"], time="ms", angle="deg")
    log = read_log(_write(tmp_path / "deg_ms.csv", 1e3 * t, np.degrees(q), tau), 2, units=units)
    assert log.step != 1e-3  # a rounding away from the reference's step
    found = identify_robot(robot, log)
    beta = reference.fit.theta
    assert np.abs(found.fit.theta - beta).max() < 1e-12 * np.abs(beta).max()  # measured: 2.5e-14


def test_validate_takes_the_same_units_and_parquet(tmp_path, arm, signals):
    urdf, _ = arm
    t, q, tau = signals
    runs = {"si": (_write(tmp_path / "si.csv", t, q, tau), []),
            "other": (_write(tmp_path / "other.parquet", 1e3 * t, np.degrees(q),
                             tau / np.array(GAINS)),
                      ["--time-unit", "ms", "--angle-unit", "deg", "--torque-gains",
                       "0.37,2.5"])}
    errors = {}
    for name, (data, options) in runs.items():
        assert main(["validate", str(data), "--robot", str(urdf), "--out",
                     str(tmp_path / name), *options]) == 0
        report = json.loads((tmp_path / name / "validation.json").read_text())
        errors[name] = report["relative_error"]["pooled"]
    assert 0.3 < errors["si"] < 1.0  # the URDF lacks the payload and friction
    assert errors["other"] == pytest.approx(errors["si"], rel=1e-9)


def test_prismatic_joints_in_mm_and_revolute_ones_in_deg(tmp_path):
    path = tmp_path / "chain.urdf"
    path.write_text(random_chain_urdf(np.random.default_rng(7), ["revolute", "prismatic"]))
    robot = read_urdf(path)
    kinds = [joint.kind for joint in robot.joints]
    assert kinds == ["revolute", "prismatic"]
    t = np.arange(2000) * 1e-3
    q = np.column_stack([0.7 * np.sin(2 * t), 0.05 * np.cos(3 * t)])  # rad, m
    u = np.column_stack([np.cos(t), 4 * np.sin(t)])
    si = read_log(_write(tmp_path / "si.csv", t, q, u), 2)
    scaled = np.column_stack([np.degrees(q[:, 0]), 1e3 * q[:, 1]])
    units = log_units(kinds, time="ms", angle="deg", length="mm", gains=(2.0, 0.5))
    log = read_log(_write(tmp_path / "mm.parquet", 1e3 * t, scaled, u / [2.0, 0.5]), 2,
                   units=units)
    for ours, expected in ((log.t, si.t), (log.q, si.q), (log.u, si.u)):
        assert np.allclose(ours, expected, rtol=1e-15, atol=1e-17)
    assert units.position[0] == math.radians(1.0) and units.position[1] == 1e-3
