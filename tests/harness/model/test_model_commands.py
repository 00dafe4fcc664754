"""identify LOG --model MODEL.toml and validate LOG --model MODEL.toml on the EMPS
benchmark's real logs, the units of a file, and every bad input (exit status 2)."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from harness.cli import main
from harness.model import read_model
from harness.model.units import si_factor

REPO = Path(__file__).resolve().parents[3]
EMPS = REPO / "examples" / "emps" / "emps.toml"
DATA = REPO / "examples" / "emps" / "data"
ESTIMATION, VALIDATION = DATA / "DATA_EMPS.mat", DATA / "DATA_EMPS_PULSES.mat"
# Published IDIM-LS values and their relative standard deviations (examples/emps/data).
PUBLISHED = {"M": (95.1089, 0.0016), "Fv": (203.5034, 0.0067), "Fc": (20.3935, 0.0129),
             "OF": (-3.1648, 0.061)}


def _parameters(folder: Path) -> dict[str, dict[str, str]]:
    with (folder / "parameters.csv").open(newline="") as handle:
        return {row["name"]: row for row in csv.DictReader(handle)}


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    out = tmp_path_factory.mktemp("emps") / "identify"
    code = main(["identify", str(ESTIMATION), "--model", str(EMPS), "--out", str(out)])
    return code, out


def test_identify_writes_the_parameters_with_units_and_standard_errors(identified):
    code, out = identified
    assert code == 0
    rows = _parameters(out)
    assert list(rows) == ["M", "Fv", "Fc", "OF"]
    assert {n: r["unit"] for n, r in rows.items()} == {"M": "kg", "Fv": "N.s/m", "Fc": "N",
                                                       "OF": "N"}
    assert all(float(r["std_error"]) > 0 for r in rows.values())
    for name in ("estimates.csv", "estimates.png", "identified.toml", "identification.json"):
        assert (out / name).stat().st_size > 0, name


def test_identify_refines_by_output_error_within_two_of_its_errors_of_idim_ls(identified):
    """Each held-out half favours the refinement on this log (measured: 0.480 % against
    0.491 % and 0.456 % against 0.462 %); the refined values lie within 2 of their standard errors of the published
    IDIM-LS values (measured: M 93.89 +- 1.6 kg, Fv 207.7 +- 9.2 N s/m, Fc 20.04 +-
    0.72 N, OF -3.325 +- 0.23 N: 0.8, 0.5, 0.5 and 0.7 of them)."""
    summary = json.loads((identified[1] / "identification.json").read_text())
    assert summary["method"] == "output error" and summary["refinement"]["applied"]
    held_out = summary["refinement"]["held_out_simulation_error"]
    halves = held_out["per_half"]
    assert all(np.array(halves["refined"]) < np.array(halves["least_squares"]))
    assert held_out["ratio"] < 1.0
    rows = _parameters(identified[1])
    for name, (value, _) in PUBLISHED.items():
        found, std = float(rows[name]["value"]), float(rows[name]["std_error"])
        assert abs(found - value) < 2 * std, (name, found, std)
        assert std < 0.1 * abs(value), name


def test_estimates_hold_positions_and_causal_velocities(identified):
    with (identified[1] / "estimates.csv").open(newline="") as handle:
        reader = csv.reader(handle)
        header = next(reader)
        first = next(reader)
    assert header == ["t", "x", "der(x)"] and len(first) == 3
    table = np.loadtxt(identified[1] / "estimates.csv", delimiter=",", skiprows=1)
    assert table.shape == (24841, 3) and np.all(np.isfinite(table))
    assert np.abs(table[:, 2]).max() == pytest.approx(0.13, rel=0.15)  # m/s, the log's top


def test_identified_model_reads_back_with_the_values_as_nominals(identified):
    model = read_model(identified[1] / "identified.toml")
    rows = _parameters(identified[1])
    assert model.nominal.tolist() == [float(rows[n]["value"]) for n in model.parameter_names]
    assert model.equations[0].text == read_model(EMPS).equations[0].text


def test_validate_on_the_pulses_log_is_the_cross_test(identified, tmp_path, capsys):
    """Measured: 5.896 %, below IDIM-LS refitted through this pipeline (5.948 %; the
    benchmark publishes 5.98 %, bench/reports/emps.py). The free run on the pulses log:
    10.4 % of the motion (open loop, for a drive that runs in closed loop)."""
    out = tmp_path / "validate"
    assert main(["validate", str(VALIDATION), "--model",
                 str(identified[1] / "identified.toml"), "--out", str(out)]) == 0
    result = json.loads((out / "validation.json").read_text())
    pooled = result["relative_error"]["pooled"]
    assert result["relative_error"]["per_equation"] == [pooled]
    assert pooled < 0.0595 and pooled == pytest.approx(0.0590, abs=5e-4)
    simulation = result["simulation_error"]
    assert simulation["diverged_at_s"] is None
    assert simulation["pooled"] == pytest.approx(0.104, abs=0.01)
    assert simulation["per_coordinate"]["x"]["unit"] == "m"
    assert result["reconstruction_error"]["pooled"] == pytest.approx(0.112, abs=0.005)
    assert (out / "validation.png").stat().st_size > 0
    assert "pooled: 5.8" in capsys.readouterr().out


MILLIMETRE_MODEL = """
[model]
coordinates = ["x"]
inputs = ["vir"]
equations = ["M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = gtau*vir"]
[parameters]
M  = { nominal = 0.1, unit = "t" }
Fv = { nominal = 0, unit = "kN.s/mm" }
Fc = { nominal = 0, unit = "kN" }
OF = { nominal = 0, unit = "kN" }
[constants]
gtau = { value = 0.03515065188, unit = "kN/V" }
[units]
x = "mm"
vir = "V"
[columns]
x = "x_mm"
vir = "vir"
"""


def _write_csv(path: Path, columns: dict[str, np.ndarray]) -> Path:
    np.savetxt(path, np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="")
    return path


def _emps_columns(names: tuple[str, str, str] = ("t", "qm", "vir")) -> dict[str, np.ndarray]:
    data = scipy.io.loadmat(ESTIMATION)
    return {names[0]: data["t"].ravel(), names[1]: data["qm"].ravel(),
            names[2]: data["vir"].ravel()}


def test_units_of_the_file_change_no_physical_value(identified, tmp_path):
    """mm for m, kN for N, t for kg: every physical value within 0.1 % (measured: 1e-13)."""
    columns = _emps_columns()
    log = _write_csv(tmp_path / "emps_mm.csv", {"t": columns["t"], "x_mm": 1e3 * columns["qm"],
                                                "vir": columns["vir"]})
    model = tmp_path / "emps_mm.toml"
    model.write_text(MILLIMETRE_MODEL)
    out = tmp_path / "mm"
    assert main(["identify", str(log), "--model", str(model), "--out", str(out)]) == 0
    metres, millimetres = _parameters(identified[1]), _parameters(out)
    for name in PUBLISHED:
        a = float(metres[name]["value"]) * si_factor(metres[name]["unit"])
        b = float(millimetres[name]["value"]) * si_factor(millimetres[name]["unit"])
        assert b == pytest.approx(a, rel=1e-3), name
        sa = float(metres[name]["std_error"]) * si_factor(metres[name]["unit"])
        sb = float(millimetres[name]["std_error"]) * si_factor(millimetres[name]["unit"])
        assert sb == pytest.approx(sa, rel=1e-3), name


# ---- bad input: exit status 2, the problem named, nothing written -----------------------

def _run(capsys, tmp_path, log: Path, model_text: str | None = None,
         command: str = "identify") -> tuple[int, str]:
    model = EMPS
    if model_text is not None:
        model = tmp_path / "model.toml"
        model.write_text(model_text)
    out = tmp_path / "out"
    code = main([command, str(log), "--model", str(model), "--out", str(out)])
    assert not out.exists() or not any(out.glob("*.csv")), "something was written"
    return code, capsys.readouterr().err


EMPS_TEXT = EMPS.read_text()


@pytest.mark.parametrize("command", ["identify", "validate"])
def test_a_model_nonlinear_in_an_unknown(tmp_path, capsys, command):
    text = EMPS_TEXT.replace("Fv*der(x)", "Fv^2*der(x)")
    code, err = _run(capsys, tmp_path, ESTIMATION, text, command)
    assert code == 2 and "not linear in the unknown parameter Fv" in err


@pytest.mark.parametrize("command", ["identify", "validate"])
def test_a_column_missing_from_the_log(tmp_path, capsys, command):
    text = EMPS_TEXT.replace('x = "qm"', 'x = "position"')
    code, err = _run(capsys, tmp_path, ESTIMATION, text, command)
    assert code == 2 and "no column 'position'" in err and "qm" in err


def test_a_column_missing_from_a_csv_log(tmp_path, capsys):
    log = _write_csv(tmp_path / "log.csv", _emps_columns(("t", "x", "vir")))
    code, err = _run(capsys, tmp_path, log)
    assert code == 2 and "no column 'qm'" in err


def test_non_finite_data(tmp_path, capsys):
    columns = _emps_columns()
    columns["qm"][1234] = np.nan
    code, err = _run(capsys, tmp_path, _write_csv(tmp_path / "log.csv", columns))
    assert code == 2 and "'qm'" in err and "NaN, infinite" in err and "line 1236" in err


def test_too_short_a_log(tmp_path, capsys):
    columns = {k: v[:300] for k, v in _emps_columns().items()}
    code, err = _run(capsys, tmp_path, _write_csv(tmp_path / "log.csv", columns))
    assert code == 2 and "too short" in err and "300 samples" in err


def test_an_unknown_the_log_never_excites(tmp_path, capsys):
    """A force input that stays 0 on the log: its coefficient cannot be identified."""
    columns = _emps_columns()
    columns["Fext"] = np.zeros_like(columns["t"])
    text = (EMPS_TEXT.replace('inputs = ["vir"]', 'inputs = ["vir", "Fext"]')
            .replace("+ OF = gtau*vir", "+ OF + K*Fext = gtau*vir")
            .replace('vir = "V"', 'vir = "V"\nFext = "N"')
            .replace('OF = { nominal = 0, unit = "N" }',
                     'OF = { nominal = 0, unit = "N" }\nK = { nominal = 0, unit = "1" }'))
    code, err = _run(capsys, tmp_path, _write_csv(tmp_path / "log.csv", columns), text)
    assert code == 2 and "does not excite K (excitation 0)" in err


def test_a_log_in_which_the_machine_never_moves(tmp_path, capsys):
    columns = _emps_columns()
    columns["qm"][:] = 0.1
    code, err = _run(capsys, tmp_path, _write_csv(tmp_path / "log.csv", columns))
    assert code == 2 and "does not excite M (excitation 0), Fv (excitation 0), Fc " \
        "(excitation 0)" in err


def test_a_log_on_which_every_column_of_the_regressor_is_zero(tmp_path, capsys):
    """No constant term either: the least squares have nothing at all to work on."""
    columns = _emps_columns()
    columns["qm"][:] = 0.1
    text = EMPS_TEXT.replace(" + OF = gtau*vir", " = gtau*vir").replace(
        'OF = { nominal = 0, unit = "N" }', "")
    code, err = _run(capsys, tmp_path, _write_csv(tmp_path / "log.csv", columns), text)
    assert code == 2 and "does not excite M (excitation 0), Fv (excitation 0), Fc " \
        "(excitation 0)" in err


def test_a_log_whose_input_is_zero(tmp_path, capsys):
    """Any multiple of the unknowns fits a zero known side: their scale cannot be told."""
    columns = _emps_columns()
    columns["vir"][:] = 0.0
    code, err = _run(capsys, tmp_path, _write_csv(tmp_path / "log.csv", columns))
    assert code == 2 and "the known side of every equation" in err and "is zero on the log" \
        in err


def test_two_unknowns_the_log_cannot_tell_apart(tmp_path, capsys):
    text = EMPS_TEXT.replace("+ OF = gtau*vir", "+ OF + OF2 = gtau*vir").replace(
        'OF = { nominal = 0, unit = "N" }',
        'OF = { nominal = 0, unit = "N" }\nOF2 = { nominal = 0, unit = "N" }')
    code, err = _run(capsys, tmp_path, ESTIMATION, text)
    assert code == 2 and "OF (excitation" in err and "OF2 (excitation" in err


def test_model_and_robot_options_do_not_mix(tmp_path, capsys):
    code = main(["identify", str(ESTIMATION), "--model", str(EMPS), "--robot", "r.urdf",
                 "--out", str(tmp_path / "o")])
    assert code == 2 and "--robot not available with --model" in capsys.readouterr().err


# ---- other shapes: simulated logs ------------------------------------------------------

def _two_mass_log(tmp_path: Path) -> Path:
    from scipy.integrate import solve_ivp

    m1, m2, c1, c2, k, d = 2.0, 1.0, 0.5, 0.5, 400.0, 1.0
    t = np.arange(0.0, 10.0, 1e-3)

    def force(t):
        return (5 * np.sin(2 * np.pi * 0.7 * t) + 3 * np.sin(2 * np.pi * 3.1 * t + 1)
                + 2 * np.sin(2 * np.pi * 7.3 * t))

    def rhs(t, s):
        x1, x2, v1, v2 = s
        spring = k * (x1 - x2) + d * (v1 - v2)
        return [v1, v2, (force(t) - c1 * v1 - spring) / m1, (-c2 * v2 + spring) / m2]
    sol = solve_ivp(rhs, (0, t[-1]), [0, 0, 0, 0], t_eval=t, method="DOP853", rtol=1e-10,
                    atol=1e-12)
    noise = 1e-6 * np.random.default_rng(0).standard_normal((len(t), 2))
    return _write_csv(tmp_path / "two_mass.csv", {"time": t, "x1": sol.y[0] + noise[:, 0],
                                                  "x2": sol.y[1] + noise[:, 1],
                                                  "F": force(t)})


def test_two_equations_one_with_a_zero_known_side(tmp_path, capsys):
    """The two-mass example on a simulated log (1 um noise): measured within 0.03 % of the
    truth; the second equation's known side is 0, so its relative error is null."""
    log = _two_mass_log(tmp_path)
    model = REPO / "examples" / "two_mass" / "two_mass.toml"
    out = tmp_path / "identify"
    assert main(["identify", str(log), "--model", str(model), "--out", str(out)]) == 0
    truth = {"m1": 2.0, "m2": 1.0, "c1": 0.5, "c2": 0.5, "k": 400.0, "d": 1.0}
    rows = _parameters(out)
    for name, value in truth.items():
        assert float(rows[name]["value"]) == pytest.approx(value, rel=5e-3), name
    header = (out / "estimates.csv").read_text().splitlines()[0].replace('"', "")
    assert header == "t,x1,der(x1),x2,der(x2)"
    assert main(["validate", str(log), "--model", str(out / "identified.toml"), "--out",
                 str(tmp_path / "validate")]) == 0
    result = json.loads((tmp_path / "validate" / "validation.json").read_text())
    first, second = result["relative_error"]["per_equation"]
    assert first < 0.01 and second is None and result["relative_error"]["pooled"] < 0.01


def test_a_model_that_explains_little_is_written_but_not_trusted(tmp_path, capsys):
    """Friction left out of EMPS: the inertia and offset reconstruct the force with a
    relative error of 69 % (measured): exit status 1, the files written."""
    text = "\n".join(line for line in EMPS_TEXT.splitlines()
                     if not line.startswith(("Fv ", "Fc "))).replace(
        "M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF", "M*der(x,2) + OF")
    model = tmp_path / "inertia_only.toml"
    model.write_text(text)
    out = tmp_path / "out"
    code = main(["identify", str(ESTIMATION), "--model", str(model), "--out", str(out)])
    assert code == 1 and "explains little" in capsys.readouterr().err
    assert list(_parameters(out)) == ["M", "OF"]


@pytest.mark.parametrize("pooled, said", [(10.3, True), (0.08, False), (None, False)])
def test_a_free_run_farther_than_the_motion_is_said_to_rank_nothing(capsys, pooled, said):
    """The two-link arm's logs (closed loop, a passive joint that sticks): the free run of
    the truth's own parameters ends 1032 % of the motion away, a score that cannot rank
    models; it is said, and the model is not called untrusted for it."""
    from harness.model.cli import _print_scores

    error = {"rms": 1.0, "unit": "rad", "relative": pooled}
    scores = {"reconstruction_error": {"pooled": None},
              "simulation_error": {"diverged_at_s": None, "pooled": pooled,
                                   "per_coordinate": {"q1": error} if pooled else {}},
              "creates_energy": None}
    assert _print_scores(scores)
    assert ("farther from the log than the motion itself" in capsys.readouterr().out) is said
