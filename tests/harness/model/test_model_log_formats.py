"""A model file's log in other units and formats: the time column in ms ([units] t),
a coordinate in deg, the log as Parquet give the parameters of the same log in s and
rad as CSV; a time unit that is no time and a file of another format exit 2."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import scipy.io

from harness.cli import main
from harness.model import read_model

REPO = Path(__file__).resolve().parents[3]
EMPS = REPO / "examples" / "emps" / "emps.toml"
ESTIMATION = REPO / "examples" / "emps" / "data" / "DATA_EMPS.mat"
# the EMPS drive as if it turned: the same numbers, rotary units
ROTARY = """
[model]
coordinates = ["x"]
inputs = ["vir"]
equations = ["M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = gtau*vir"]
[parameters]
M  = { nominal = 100, unit = "kg.m^2" }
Fv = { nominal = 0, unit = "N.m.s/rad" }
Fc = { nominal = 0, unit = "N.m" }
OF = { nominal = 0, unit = "N.m" }
[constants]
gtau = { value = 35.15065188, unit = "N.m/V" }
[units]
x = "UNIT"
vir = "V"
"""


def _values(folder: Path) -> np.ndarray:
    with (folder / "parameters.csv").open(newline="") as handle:
        return np.array([float(row["value"]) for row in csv.DictReader(handle)])


def _identify(tmp_path: Path, log: Path, model: Path, name: str) -> np.ndarray:
    out = tmp_path / name
    assert main(["identify", str(log), "--model", str(model), "--out", str(out)]) == 0
    return _values(out)


@pytest.fixture(scope="module")
def emps() -> pd.DataFrame:
    data = scipy.io.loadmat(ESTIMATION)
    return pd.DataFrame({"t": data["t"].ravel(), "qm": data["qm"].ravel(),
                         "vir": data["vir"].ravel()})


def test_time_in_ms_and_parquet_give_the_same_parameters(tmp_path, capsys, emps):
    emps.to_csv(tmp_path / "s.csv", index=False, float_format="%.17g")
    reference = _identify(tmp_path, tmp_path / "s.csv", EMPS, "s")  # the values themselves:
    # test_model_commands; here, that a unit of the log changes none of them
    milliseconds = emps.assign(t=1e3 * emps.t)
    milliseconds.to_csv(tmp_path / "ms.csv", index=False, float_format="%.17g")
    milliseconds.to_parquet(tmp_path / "ms.parquet")
    model = tmp_path / "emps_ms.toml"
    model.write_text(EMPS.read_text().replace('[units]\n', '[units]\nt = "ms"\n'))
    assert read_model(model).time_unit == "ms"
    in_ms = _identify(tmp_path, tmp_path / "ms.csv", model, "ms")
    # the output-error refinement's iterations carry the rounding of the scaled time to
    # about 1e-8 (its standard errors are 2 % of the values)
    assert np.allclose(in_ms, reference, rtol=1e-6, atol=0), in_ms / reference - 1
    parquet = _identify(tmp_path, tmp_path / "ms.parquet", model, "parquet")
    assert np.array_equal(parquet, in_ms)  # the same numbers from either format
    # identified.toml keeps the time unit, and reads back; validate takes it and Parquet
    assert read_model(tmp_path / "ms" / "identified.toml").time_unit == "ms"
    pooled = {}
    for name, log, model in (("s", "s.csv", tmp_path / "s" / "identified.toml"),
                             ("ms", "ms.parquet", tmp_path / "ms" / "identified.toml")):
        out = tmp_path / f"validate_{name}"
        assert main(["validate", str(tmp_path / log), "--model", str(model), "--out",
                     str(out)]) == 0
        pooled[name] = json.loads((out / "validation.json").read_text())["relative_error"]
    assert pooled["ms"]["pooled"] == pytest.approx(pooled["s"]["pooled"], rel=1e-9)
    assert 0.0 < pooled["s"]["pooled"] < 0.5
    # without [units] t the log in ms is read as seconds: other values (M 1e6 times
    # larger), and a warning that says how to give the unit (exit status 1)
    out = tmp_path / "wrong"
    code = main(["identify", str(tmp_path / "ms.csv"), "--model", str(EMPS), "--out", str(out)])
    assert code == 1
    assert "samples 1 s apart" in capsys.readouterr().err
    # on the stretched clock the cross-validation's runs are shorter in samples (at most
    # 40 of 1 s, not 200 of 1 ms), so it may choose another pipeline: measured, spectral
    # 0.02 Hz with the friction rows, M 1.4 % from the reference (its standard error 1.7 %)
    assert _values(out)[0] == pytest.approx(1e6 * reference[0], rel=0.03)


def test_a_coordinate_in_deg_gives_the_values_of_one_in_rad(tmp_path, emps):
    emps.to_csv(tmp_path / "rad.csv", index=False, float_format="%.17g")
    emps.assign(qm=np.degrees(emps.qm)).to_parquet(tmp_path / "deg.parquet")
    models = {}
    for unit in ("rad", "deg"):
        models[unit] = tmp_path / f"{unit}.toml"
        models[unit].write_text(ROTARY.replace("UNIT", unit) + '[columns]\nx = "qm"\n')
    rad = _identify(tmp_path, tmp_path / "rad.csv", models["rad"], "rad")
    deg = _identify(tmp_path, tmp_path / "deg.parquet", models["deg"], "deg")
    assert np.allclose(deg, rad, rtol=1e-6, atol=0), deg / rad - 1


@pytest.mark.parametrize("unit, words", [
    ("deg", ["[units] t", "'deg' is not a unit of [time]"]),
    ("mm", ["[units] t", "'mm' is not a unit of [time]"]),
    ("fortnights2", ["t (the log's time column)", "not a unit pint knows"]),
])
def test_a_time_unit_that_is_no_time_exits_2(tmp_path, capsys, unit, words):
    model = tmp_path / "model.toml"
    model.write_text(EMPS.read_text().replace('[units]\n', f'[units]\nt = "{unit}"\n'))
    code = main(["identify", str(ESTIMATION), "--model", str(model), "--out",
                 str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2, err
    for word in words:
        assert word in err, err
    assert not (tmp_path / "o").exists()


def test_units_with_the_time_alone_scale_the_time_and_check_nothing(tmp_path):
    text = EMPS.read_text()
    start, end = text.index("[units]"), text.index("[columns]")
    model = tmp_path / "model.toml"
    model.write_text(text[:start] + '[units]\nt = "ms"\n\n' + text[end:])
    read = read_model(model)
    assert read.time_unit == "ms" and read.units == {}


@pytest.mark.parametrize("command", ["identify", "validate"])
@pytest.mark.parametrize("name", ["log.xlsx", "log.json", "log.h5", "log"])
def test_a_log_of_another_format_exits_2_naming_it(tmp_path, capsys, command, name):
    log = tmp_path / name
    log.write_text("t,qm,vir\n0,0,0\n")
    code = main([command, str(log), "--model", str(EMPS), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert str(log) in err and "CSV (.csv, .txt), Parquet (.parquet, .pq), MATLAB (.mat)" in err


def test_a_jittering_clock_is_resampled_and_identifies_as_the_even_log(tmp_path, capsys, emps):
    """EMPS sampled at stamps moved by up to 30 % of a step (the positions interpolated
    onto them by cubic splines, the voltage linearly): identify resamples the log onto
    even steps, says so, and lands within a standard error of the even log's values."""
    rng = np.random.default_rng(7)
    t = emps.t.to_numpy()
    stamps = t + 0.3e-3 * rng.uniform(-1, 1, len(t))
    stamps[0], stamps[-1] = t[0], t[-1]
    from scipy.interpolate import make_interp_spline
    jittered = pd.DataFrame({"t": stamps, "qm": make_interp_spline(t, emps.qm, k=3)(stamps),
                             "vir": np.interp(stamps, t, emps.vir)})
    emps.to_csv(tmp_path / "even.csv", index=False, float_format="%.17g")
    jittered.to_csv(tmp_path / "jittered.csv", index=False, float_format="%.17g")
    even = _identify(tmp_path, tmp_path / "even.csv", EMPS, "even")
    capsys.readouterr()
    moved = _identify(tmp_path, tmp_path / "jittered.csv", EMPS, "jittered")
    assert "the clock jitters" in capsys.readouterr().out
    summary = json.loads((tmp_path / "jittered" / "identification.json").read_text())
    assert "resampled onto even steps" in summary["resampled"]
    errors = np.array([p["std_error"] for p in summary["parameters"].values()])
    assert np.all(np.abs(moved - even) < errors), (moved - even) / errors
