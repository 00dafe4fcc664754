"""Declared parameter ranges (``positive = true``, ``range = [a, b]``): read and written
back, kept by identify's least squares and refinement (the minimum inside the box, the
others' standard errors with the held ones fixed), by the model FMU's identifier (the same
minimum with its information matrix), and said when the log pushes against them; and the
model FMU's flag of a model that creates energy."""
from __future__ import annotations

import json
from pathlib import Path

import fmpy
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from harness.cli import main
from harness.model import read_model
from harness.model.errors import ModelFileError
from harness.model.fit import fit
from harness.model.writer import model_toml

MASS, DAMPING, STIFFNESS = 1.0, 0.8, 40.0  # the truth of the simulated oscillator

MODEL = """\
[model]
coordinates = ["x"]
inputs = ["F"]
equations = ["m*der(x,2) + d*der(x) + k*x = F"]

[parameters]
m = {{ nominal = 1.2{m} }}
d = {{ nominal = 0.5{d} }}
k = {{ nominal = 30.0{k} }}
"""


def _model(path: Path, m: str = "", d: str = "", k: str = "") -> Path:
    path.write_text(MODEL.format(m=m, d=d, k=k), encoding="utf-8")
    return path


@pytest.mark.parametrize("entry,message", [
    (", positive = true, range = [0, 1]", "not both"),
    (", range = [3, 1]", "is empty"),
    (", range = [0]", "must be a list [lower, upper]"),
    (", range = [0, \"a\"]", "the upper end of its range must be a number"),
    (", range = [0, nan]", "the upper end of its range must be a number"),
    (", range = [2, 3]", "the nominal value 0.5 is outside its declared range [2, 3]"),
    (", positive = 1", "positive must be true or false"),
    (", optional = true, range = [0.1, 1]", "optional means it may be left out at 0"),
])
def test_a_bad_range_is_refused_by_name(tmp_path, entry, message):
    with pytest.raises(ModelFileError) as caught:
        read_model(_model(tmp_path / "m.toml", d=entry))
    assert message in str(caught.value) and "parameter d" in str(caught.value)


def test_ranges_read_and_write_back(tmp_path):
    model = read_model(_model(tmp_path / "m.toml", m=", positive = true",
                              d=", range = [0, 10]", k=", range = [-inf, 50]"))
    lower, upper = model.bounds
    np.testing.assert_array_equal(lower, [0.0, 0.0, -np.inf])
    np.testing.assert_array_equal(upper, [np.inf, 10.0, 50.0])
    again = tmp_path / "again.toml"
    again.write_text(model_toml(model, model.nominal), encoding="utf-8")
    assert read_model(again).parameters == model.parameters
    assert "m = { nominal = 1.2, unit = \"\", positive = true }" in again.read_text()


def test_the_bounded_fit_is_the_fit_with_the_held_unknown_fixed():
    """Least squares inside the box: the unknown pushed below 0 is held there, the others
    are the least squares with it fixed (values and sandwich standard errors), and the
    estimate without the range is kept beside."""
    rng = np.random.default_rng(1)
    Y = rng.normal(size=(500, 1, 3))
    Y[:, 0, 1] += 0.6 * Y[:, 0, 0]  # correlated columns: the held one moves the other
    r = Y @ np.array([1.0, -0.05, 2.0]) + 0.1 * rng.normal(size=(500, 1))
    bounds = (np.array([0.0, 0.0, -np.inf]), np.full(3, np.inf))
    bounded = fit(Y, r, np.ones(3), bounds=bounds)
    fixed = fit(Y[:, :, [0, 2]], r, np.ones(2))
    assert bounded.theta[1] == 0.0 and list(bounded.at_bound) == [0, -1, 0]
    np.testing.assert_allclose(bounded.theta[[0, 2]], fixed.theta, rtol=1e-9)
    np.testing.assert_allclose(bounded.std_error[[0, 2]], fixed.std_error, rtol=1e-6)
    assert bounded.std_error[1] == 0.0
    free = fit(Y, r, np.ones(3))
    assert free.at_bound is None and free.theta[1] < -0.03
    np.testing.assert_allclose(bounded.unbounded, free.theta, rtol=1e-12)


def _oscillator_log(path: Path, seconds: float = 10.0, rate: float = 1000.0) -> Path:
    """m x'' + d x' + k x = F under a sum of sines, the position with 1e-4 m of noise."""
    t = np.arange(0.0, seconds, 1.0 / rate)
    phases = np.arange(5)
    frequencies = np.array([0.3, 0.7, 1.1, 1.9, 2.3])

    def force(time):
        return np.sum(np.sin(2 * np.pi * frequencies * np.atleast_1d(time)[:, None] + phases),
                      axis=1)

    solution = solve_ivp(lambda time, s: [s[1], (force(time)[0] - DAMPING * s[1]
                                                 - STIFFNESS * s[0]) / MASS],
                         (0.0, seconds), [0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-12)
    x = solution.y[0] + 1e-4 * np.random.default_rng(3).standard_normal(len(t))
    np.savetxt(path, np.column_stack([t, x, force(t)]), delimiter=",", header="t,x,F",
               comments="", fmt="%.12g")
    return path


@pytest.fixture(scope="module")
def oscillator(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ranges")
    return folder, _oscillator_log(folder / "log.csv")


def test_identify_holds_a_range_the_log_pushes_against(oscillator, capsys):
    """k declared within [0, 35] on a log of k = 40: identify holds k at 35 with exit 1 and a
    warning that gives the least squares without the range (40, many standard errors
    outside); identification.json records it."""
    folder, log = oscillator
    model = _model(folder / "narrow.toml", m=", positive = true", k=", range = [0, 35]")
    code = main(["identify", str(log), "--model", str(model), "--out", str(folder / "narrow")])
    out, err = capsys.readouterr()
    assert code == 1, err
    summary = json.loads((folder / "narrow" / "identification.json").read_text())
    held = summary["held_at_range"]
    assert list(held) == ["k"] and held["k"]["end"] == "upper" and held["k"]["significant"]
    assert held["k"]["least_squares_without_range"] == pytest.approx(STIFFNESS, rel=0.02)
    values = summary["parameters"]
    assert values["k"]["value"] == 35.0 and values["k"]["std_error"] == 0.0
    assert values["m"]["std_error"] > 0.0
    assert "k is held at the upper end of its declared range, 35" in err
    assert "(held at the upper end of its range)" in out


def test_a_range_the_truth_keeps_changes_nothing(oscillator, capsys):
    """Ranges that contain the answer: the same estimate as without them, exit 0 (the
    refinement's solver takes another path inside bounds: within a hundredth of a standard
    error; measured 4e-4 of one)."""
    folder, log = oscillator
    plain = _model(folder / "plain.toml")
    ranged = _model(folder / "ranged.toml", m=", positive = true", d=", range = [0, 5]",
                    k=", positive = true")
    results = []
    for model in (plain, ranged):
        out = folder / model.stem
        assert main(["identify", str(log), "--model", str(model), "--out", str(out)]) == 0
        results.append(json.loads((out / "identification.json").read_text()))
    for name in ("m", "d", "k"):
        free, kept = results[0]["parameters"][name], results[1]["parameters"][name]
        assert abs(kept["value"] - free["value"]) <= 0.01 * free["std_error"], name
        assert kept["std_error"] == pytest.approx(free["std_error"], rel=1e-3), name
    assert results[1]["held_at_range"] == {}
    assert results[0]["parameters"]["k"]["value"] == pytest.approx(STIFFNESS, rel=0.01)


def _run_fmu(fmu: Path, log: Path, outputs: list[str], **start) -> np.ndarray:
    data = np.genfromtxt(log, delimiter=",", names=True)
    signals = np.zeros(len(data), dtype=[("time", float), ("x", float), ("F", float)])
    signals["time"], signals["x"], signals["F"] = data["t"], data["x"], data["F"]
    step = float(data["t"][1] - data["t"][0])
    return fmpy.simulate_fmu(str(fmu), stop_time=float(data["t"][-1]), step_size=step,
                             output_interval=step, input=signals,
                             start_values={"observer.h": step, **start}, output=outputs)


@pytest.mark.parametrize("version", [2, 3])
def test_the_fmu_keeps_the_range_as_identify_does(oscillator, capfd, version):
    """The model FMU holds k at 35 (parameters_held = 1, k_std = 0, a warning through the
    FMI logger) and its m ends within 3 combined standard errors of identify's m with k
    held (the same minimum inside the box, with the identifier's information)."""
    folder, log = oscillator
    model = _model(folder / "narrow_fmu.toml", k=", range = [0, 35]")
    out = folder / f"fmu{version}"
    assert main(["fmu", "--model", str(model), "--out", str(out), "--fmi-version",
                 str(version)]) == 0
    capfd.readouterr()
    result = _run_fmu(out / "narrow_fmu.fmu", log, ["m", "d", "k", "m_std", "k_std",
                                                     "observer.parameters_held"])
    messages = capfd.readouterr().out
    assert result["k"][-1] == 35.0 and result["k_std"][-1] == 0.0
    assert result["observer.parameters_held"][-1] == 1
    assert "held at an end of the range the model file declares" in messages
    assert "k at its upper end 35" in messages  # the parameter by its name
    offline = folder / "narrow_offline"
    main(["identify", str(log), "--model", str(model), "--out", str(offline), "--refine",
          "none"])
    m = json.loads((offline / "identification.json").read_text())["parameters"]["m"]
    combined = np.hypot(m["std_error"], result["m_std"][-1])
    assert abs(result["m"][-1] - m["value"]) <= 3 * combined, (result["m"][-1], m, combined)


def test_the_fmu_flags_a_model_that_creates_energy(oscillator, capfd):
    """The identifier off, the published model is the nominal one: a negative damping is
    flagged (negative_damping, and one warning once it has stood for 1 s), a positive one
    is not."""
    folder, log = oscillator
    flags = {}
    for sign in (-1, 1):
        name = "gains" if sign < 0 else "takes"
        path = folder / f"{name}.toml"
        path.write_text(MODEL.format(m="", d="", k="").replace("nominal = 0.5",
                                                                f"nominal = {0.5 * sign}"),
                        encoding="utf-8")
        assert main(["fmu", "--model", str(path), "--out", str(folder / name)]) == 0
        capfd.readouterr()
        result = _run_fmu(folder / name / f"{name}.fmu", log, ["observer.negative_damping"],
                          **{"observer.identifier": 0})
        messages = capfd.readouterr().out
        flags[sign] = (bool(np.all(result["observer.negative_damping"][1:])),
                       messages.count("created energy"))
    assert flags[-1] == (True, 1) and flags[1] == (False, 0), flags


def test_validate_says_a_model_creates_energy(oscillator, capsys):
    """A negative damping: validate exits 1 with a warning and records the share of the
    log's positions where the friction gives energy (all of them); the positive one is
    not flagged."""
    folder, log = oscillator
    for sign, code, share in ((-1, 1, 1.0), (1, 0, 0.0)):
        path = folder / f"validate{sign}.toml"
        path.write_text(MODEL.format(m="", d="", k="").replace("nominal = 0.5",
                                                                f"nominal = {0.5 * sign}"),
                        encoding="utf-8")
        out = folder / f"validated{sign}"
        assert main(["validate", str(log), "--model", str(path), "--out", str(out)]) == code
        energy = json.loads((out / "validation.json").read_text())["creates_energy"]
        assert energy["share"] == share and energy["states"] == 200
        assert ("creates energy" in capsys.readouterr().err) == (sign < 0)
