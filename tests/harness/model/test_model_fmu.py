"""The FMU of a model file (``sto-harness fmu --model``, harness/model/fmu_export.py): a
valid FMU of FMI 2 and 3 whose variables carry the model's names and units, which
identifies the model from a log through fmpy as ``identify`` does, and refuses what it
cannot be built for with exit status 2."""
from __future__ import annotations

import shutil
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp

from bench.cases import oscillator
from bench.reports import fmu_agreement
from harness.cli import main
from harness.model import read_model
from harness.model.cli import identify_model
from harness.model.log import read_log

REPO = Path(__file__).resolve().parents[3]
EMPS = REPO / "examples" / "emps"
TWO_MASS = REPO / "examples" / "two_mass" / "two_mass.toml"


def export(model: Path, out: Path, *options: str) -> Path:
    assert main(["fmu", "--model", str(model), "--out", str(out), *options]) == 0
    return out / f"{model.stem}.fmu"


@pytest.fixture(scope="module")
def emps_fmus(tmp_path_factory):
    out = tmp_path_factory.mktemp("emps_fmu")
    return {2: export(EMPS / "emps.toml", out / "2"), 3: export(EMPS / "emps.toml", out / "3",
                                                                  "--fmi-version", "3")}


@pytest.mark.parametrize("version", [2, 3])
def test_the_fmu_is_valid_and_speaks_the_models_names(emps_fmus, version):
    fmu = emps_fmus[version]
    assert validate_fmu(str(fmu)) == []
    variables = {v.name: v for v in fmpy.read_model_description(str(fmu)).modelVariables}
    assert variables["x"].causality == "input" and variables["x"].unit == "m"
    assert variables["vir"].causality == "input" and variables["vir"].unit == "V"
    assert variables["der(x)"].causality == "output" and variables["der(x)"].unit == "m/s"
    for name, unit in (("M", "kg"), ("Fv", "N.s/m"), ("Fc", "N"), ("OF", "N")):
        assert variables[name].causality == "output" and variables[name].unit == unit
        assert variables[f"{name}_std"].unit == unit
        assert variables[f"{name}_excitation"].causality == "output"
    assert variables["observer.h"].causality == "parameter"
    # the generic variables the model does not use are left out
    assert not any(n.startswith(("position_", "theta_", "input_")) for n in variables)
    with zipfile.ZipFile(fmu) as archive:
        program = archive.read("resources/model.txt").decode()
        assert program.startswith("sto-term-program 1") and "sizes 1 1 4" in program
        assert not any(n.startswith("extra/") for n in archive.namelist())


def run_log(fmu: Path, t, positions: dict, inputs: dict, outputs: list[str], **start):
    names = [*positions, *inputs]
    signals = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in names])
    signals["time"] = t - t[0]
    for n, values in {**positions, **inputs}.items():
        signals[n] = values
    step = float(t[1] - t[0])
    return fmpy.simulate_fmu(str(fmu), stop_time=float(signals["time"][-1]), step_size=step,
                             output_interval=step, input=signals,
                             start_values={"observer.h": step, **start}, output=outputs)


def test_the_fmu_identifies_emps_as_identify_does(emps_fmus):
    """The FMU's fixed-lag least squares against identify's answer, refined by output
    error: 0.14 to 1.06 combined standard errors (measured; within 3).  The FMU leaves out
    the rows where the drive is slow or reverses (its friction rows), which identify's
    cross-validation declines on this log, so only the inertia is as identify's
    least-squares stage (M -0.05 %, measured; Fv -3.1 %, Fc +3.2 %, OF +6.2 %).  Each
    parameter's excitation as identify's figure (measured 0.386 against 0.439 for Fv and
    Fc, which the rows near the reversals separate most; the others 1.0)."""
    model = read_model(EMPS / "emps.toml")
    log = read_log(EMPS / "data" / "DATA_EMPS.mat", model)
    identified = identify_model(model, log)
    found = identified.least_squares
    offline, offline_std = found.theta, found.std_error
    names = [p.name for p in model.parameters]
    result = run_log(emps_fmus[2], log.t, {"x": log.q[:, 0]}, {"vir": log.inputs[:, 0]},
                     names + [f"{n}_std" for n in names] + [f"{n}_excitation" for n in names]
                     + ["observer.identifier_active", "observer.parameters_not_excited"])
    assert result["observer.identifier_active"][-1]
    assert result["observer.parameters_not_excited"][-1] == 0
    for k, name in enumerate(names):
        excitation = result[f"{name}_excitation"][-1]
        assert abs(excitation - found.excitation[k]) <= 0.07, (name, excitation, found.excitation)
    assert abs(result["M"][-1] - offline[0]) <= 0.005 * offline[0], (result["M"][-1], offline[0])
    for k, name in enumerate(names):
        value, std = result[name][-1], result[f"{name}_std"][-1]
        combined = np.hypot(std, identified.std_error[k])
        assert abs(value - identified.theta[k]) <= 3 * combined, (name, value, combined)
        # error bars of the same size: measured 0.86 to 1.82 times identify's (sandwich both)
        assert 0.5 * offline_std[k] < std < 4.0 * offline_std[k], (name, std, offline_std[k])
    # FMI 3: the same binary core, the same numbers
    fmi3 = run_log(emps_fmus[3], log.t[:5000], {"x": log.q[:5000, 0]},
                   {"vir": log.inputs[:5000, 0]}, names)
    fmi2 = run_log(emps_fmus[2], log.t[:5000], {"x": log.q[:5000, 0]},
                   {"vir": log.inputs[:5000, 0]}, names)
    for name in names:
        assert fmi3[name][-1] == fmi2[name][-1]


TRUTH = {"m1": 2.4, "m2": 0.8, "c1": 0.8, "c2": 0.3, "k": 350.0, "d": 1.5}


def two_mass_log(seconds=20.0, rate=1000.0):
    p = TRUTH
    freqs = np.array([0.3, 0.9, 2.1, 4.3, 7.7])

    def force(t):
        return 20.0 * np.sum(np.sin(2 * np.pi * freqs * t + np.arange(5)), axis=0)

    def rhs(t, s):
        x1, x2, v1, v2 = s
        spring = p["k"] * (x1 - x2) + p["d"] * (v1 - v2)
        return [v1, v2, (force(t) - p["c1"] * v1 - spring) / p["m1"],
                (-p["c2"] * v2 + spring) / p["m2"]]

    t = np.arange(0.0, seconds, 1.0 / rate)
    sol = solve_ivp(rhs, (0.0, seconds), [0, 0, 0, 0], t_eval=t, rtol=1e-10, atol=1e-12,
                    method="DOP853")
    return t, sol.y[0], sol.y[1], np.array([force(x) for x in t])


def test_the_fmu_identifies_a_coupled_two_mass_system(tmp_path):
    """n = 2, the spring and damper in both equations. Measured: worst 0.3 % (k)."""
    fmu = export(TWO_MASS, tmp_path)
    t, x1, x2, F = two_mass_log()
    names = list(TRUTH)
    result = run_log(fmu, t, {"x1": x1, "x2": x2}, {"F": F}, names)
    for name in names:
        assert abs(result[name][-1] - TRUTH[name]) <= 0.02 * TRUTH[name], \
            (name, result[name][-1], TRUTH[name])


def test_the_fmu_identifies_an_oscillator_near_its_sample_rate(tmp_path):
    """The cubic oscillator of bench/cases/oscillator.py (resonance near fs/9, 0.5 % noise,
    65,000 samples), where no causal observer at that rate tracks the motion: through the
    fixed-lag window (the default) m, d and k within 0.5 % of the truth and k3 within 3 %
    (measured m -0.15 %, d +0.01 %, k +0.29 %, k3 -2.7 % at a chosen 122 Hz; k3's is the
    regularization rho pulling it toward its nominal 0, y^3's column being small in SI:
    with rho = 1e-15 and exact positions every parameter is within 0.03 %); through the
    observer's velocities (regression = 0) m came out at 0.089."""
    model = tmp_path / "oscillator.toml"
    model.write_text(oscillator.MODEL_TOML, encoding="utf-8")
    fmu = export(model, tmp_path / "fmu")
    log = oscillator.make_log(0)
    names = list(oscillator.NAMES)
    outputs = names + ["observer.identifier_cutoff", "observer.negative_damping"]
    result = run_log(fmu, log.t, {"y": log.y}, {"u": log.u}, outputs)
    assert result["observer.identifier_cutoff"][-1] == pytest.approx(0.2 * oscillator.RATE)
    assert not result["observer.negative_damping"][-1]
    for name in names:
        truth, tolerance = oscillator.TRUTH[name], 0.03 if name == "k3" else 0.005
        assert abs(result[name][-1] - truth) <= tolerance * truth, (name, result[name][-1], truth)
    causal = run_log(fmu, log.t, {"y": log.y}, {"u": log.u}, ["m"], **{"observer.regression": 0})
    assert abs(causal["m"][-1] - 1.0) > 0.5  # what the window is for


def test_a_held_input_reaches_the_fmu_as_declared(tmp_path):
    """[log] inputs = "held" reaches the FMU (resources/model.txt: inputs_held 1), whose
    window then smooths the staircase the controller's output draws: on a simulated
    EMPS-like drive in closed loop at 1 kHz (bench/reports/fmu_agreement.py, its input
    held over each sample), M measured -0.039 % from the truth with the declaration,
    +0.014 % without (noise-free -0.034 and +0.020 %: at 1 kHz the half sample moves M by
    less than the window's other errors, once the drive's slow and reversing rows are
    left out; 0.5 % and 0.7 % before that)."""
    sampled = EMPS / "emps.toml"
    held = tmp_path / "emps.toml"
    held.write_text(sampled.read_text(encoding="utf-8") + '\n[log]\ninputs = "held"\n',
                    encoding="utf-8")
    fmus = {name: export(path, tmp_path / name) for name, path in
            (("held", held), ("sampled", sampled))}
    with zipfile.ZipFile(fmus["held"]) as fmu:
        assert "\ninputs_held 1\n" in fmu.read("resources/model.txt").decode()
    with zipfile.ZipFile(fmus["sampled"]) as fmu:
        assert "inputs_held" not in fmu.read("resources/model.txt").decode()
    t, x, vir = fmu_agreement.simulate(0, 20.0)
    found = {name: run_log(fmu, t, {"x": x}, {"vir": vir}, ["M"])["M"][-1]
             for name, fmu in fmus.items()}
    truth = fmu_agreement.TRUTH["M"]
    assert found["held"] != found["sampled"], found
    assert all(abs(m - truth) < 1e-3 * truth for m in found.values()), found


CHAIN_MASSES = (1.0, 1.3, 0.8, 1.6, 1.1, 0.9, 1.4)  # kg, the truth
CHAIN_DAMPING, CHAIN_SPRING = 0.7, 200.0   # N.s/m (unknown), N/m (known)


def test_parameters_the_log_does_not_tell_apart_are_reported(tmp_path, capfd):
    """Two stiffness terms of the same column (k_a x + k_b x): each one's excitation
    below 0.001 (measured 3.9e-4: the identifier's ridge), ``observer.parameters_not_excited``
    2, and one warning naming one of them; m and d, which the log excites, clearly above
    (measured 0.25 for m, whose column near the resonance is close to k's, and 1.0 for d)."""
    model = tmp_path / "split.toml"
    model.write_text('[model]\ncoordinates = ["x"]\ninputs = ["u"]\n'
                     'equations = ["m*der(x,2) + d*der(x) + k_a*x + k_b*x = u"]\n[parameters]\n'
                     'm = { nominal = 1 }\nd = { nominal = 1 }\nk_a = { nominal = 50 }\n'
                     'k_b = { nominal = 50 }\n', encoding="utf-8")
    fmu = export(model, tmp_path / "fmu")
    capfd.readouterr()
    t = np.arange(0.0, 6.0, 1e-3)

    def force(time):
        return sum(np.sin(2 * np.pi * f * time + f) for f in (0.7, 1.9, 4.1, 8.3))

    solution = solve_ivp(lambda time, s: [s[1], force(time) - 0.5 * s[1] - 120.0 * s[0]],
                         (0.0, t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-12)
    names = ["m", "d", "k_a", "k_b"]
    result = run_log(fmu, t, {"x": solution.y[0]}, {"u": force(t)},
                     [f"{n}_excitation" for n in names] + ["observer.parameters_not_excited"])
    messages = [m for m in capfd.readouterr().out.splitlines() if "not excited" in m]
    excitation = {n: result[f"{n}_excitation"][-1] for n in names}
    assert excitation["k_a"] < 1e-3 and excitation["k_b"] < 1e-3, excitation
    assert excitation["m"] > 0.1 and excitation["d"] > 0.5, excitation
    assert result["observer.parameters_not_excited"][-1] == 2
    assert len(messages) == 1 and "2 parameter(s) not excited" in messages[0], messages
    assert " k_a " in messages[0] or " k_b " in messages[0], messages


def chain_model(path: Path) -> Path:
    """Seven masses on a line, neighbours joined by springs of known stiffness, each
    pushed by its own force: n = 7, the observer's coordinates in two groups."""
    n = len(CHAIN_MASSES)
    equations = []
    for i in range(1, n + 1):
        springs = " + ".join(f"k*(x{i} - x{j})" for j in (i - 1, i + 1) if 1 <= j <= n)
        equations.append(f'"m{i}*der(x{i},2) + c*der(x{i}) + {springs} = u{i}"')
    parameters = "\n".join(f'm{i} = {{ nominal = 1.2, unit = "kg" }}' for i in range(1, n + 1))
    path.write_text(
        f"[model]\ncoordinates = {[f'x{i}' for i in range(1, n + 1)]!r}\n"
        f"inputs = {[f'u{i}' for i in range(1, n + 1)]!r}\n"
        f"equations = [{', '.join(equations)}]\n[parameters]\n{parameters}\n"
        f'c = {{ nominal = 0.5, unit = "N.s/m" }}\n[constants]\nk = {CHAIN_SPRING}\n')
    return path


def test_the_fmu_identifies_seven_coupled_coordinates(tmp_path):
    """n = 7 (the most a model file's FMU takes): every mass and the damping within 2 %."""
    n, masses = len(CHAIN_MASSES), np.array(CHAIN_MASSES)
    rng = np.random.default_rng(3)
    freqs, phases = rng.uniform(0.3, 6.0, (n, 4)), rng.uniform(0, 2 * np.pi, (n, 4))

    def forces(t):
        return 10.0 * np.sin(2 * np.pi * freqs * np.asarray(t)[..., None, None] + phases).sum(-1)

    def rhs(t, s):
        x, v = s[:n], s[n:]
        spring = CHAIN_SPRING * (2 * x - np.r_[x[1:], 0.0] - np.r_[0.0, x[:-1]])
        spring[0] -= CHAIN_SPRING * x[0]   # the ends have one neighbour
        spring[-1] -= CHAIN_SPRING * x[-1]
        return np.r_[v, (forces(t) - CHAIN_DAMPING * v - spring) / masses]

    t = np.arange(0.0, 20.0, 1e-3)
    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(2 * n), t_eval=t, rtol=1e-10, atol=1e-12,
                    method="DOP853")
    u = forces(t)
    fmu = export(chain_model(tmp_path / "chain.toml"), tmp_path)
    names = [f"m{i}" for i in range(1, n + 1)] + ["c"]
    result = run_log(fmu, t, {f"x{i + 1}": sol.y[i] for i in range(n)},
                     {f"u{i + 1}": u[:, i] for i in range(n)}, names)
    for name, truth in zip(names, [*CHAIN_MASSES, CHAIN_DAMPING]):
        assert abs(result[name][-1] - truth) <= 0.02 * truth, (name, result[name][-1], truth)


def test_mff_is_the_fmus_default_when_asked(tmp_path):
    fmu = export(TWO_MASS, tmp_path, "--identifier", "mff")
    variables = {v.name: v for v in fmpy.read_model_description(str(fmu)).modelVariables}
    assert variables["observer.identifier"].start == "2"
    slave = FMU2Slave(guid=fmpy.read_model_description(str(fmu)).guid,
                      unzipDirectory=fmpy.extract(str(fmu)), modelIdentifier="ModelObserver",
                      instanceName="mff")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    try:
        vr = variables["observer.identifier"].valueReference
        assert slave.getInteger([vr]) == [2]
    finally:
        slave.freeInstance()


def test_a_state_of_another_model_file_is_refused(tmp_path, capsys):
    """The same binary with another model file: its state is refused, not reinterpreted."""
    first = export(EMPS / "emps.toml", tmp_path / "a")
    changed = tmp_path / "emps.toml"
    changed.write_text((EMPS / "emps.toml").read_text().replace("nominal = 100", "nominal = 90"))
    second = export(changed, tmp_path / "b")
    slaves = []
    for fmu in (first, second):
        description = fmpy.read_model_description(str(fmu))
        slave = FMU2Slave(guid=description.guid, unzipDirectory=fmpy.extract(str(fmu)),
                          modelIdentifier="ModelObserver", instanceName=fmu.parent.name)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slaves.append(slave)
    try:
        state = slaves[0].serializeFMUstate(slaves[0].getFMUstate())
        with pytest.raises(FMICallException):
            slaves[1].setFMUstate(slaves[1].deSerializeFMUstate(state))
        assert "written with another model file" in capsys.readouterr().out
        slaves[0].setFMUstate(slaves[0].deSerializeFMUstate(state))  # its own: accepted
        slaves[0].terminate()
    finally:
        for slave in slaves:
            slave.freeInstance()


def test_an_fmu_without_its_model_file_does_not_instantiate(tmp_path, emps_fmus):
    unzipped = Path(fmpy.extract(str(emps_fmus[2]), unzipdir=str(tmp_path / "fmu")))
    (unzipped / "resources" / "model.txt").unlink()
    description = fmpy.read_model_description(str(emps_fmus[2]))
    slave = FMU2Slave(guid=description.guid, unzipDirectory=str(unzipped),
                      modelIdentifier="ModelObserver", instanceName="missing")
    with pytest.raises(Exception, match="Failed to instantiate"):
        slave.instantiate(loggingOn=True)
    shutil.rmtree(unzipped)


def write_model(path: Path, coordinates: int, extra_parameter: str = "") -> Path:
    names = [f"q{i}" for i in range(1, coordinates + 1)]
    equations = ", ".join(f'"m{i}*der({c},2) = u"' for i, c in enumerate(names, start=1))
    parameters = "\n".join(f"m{i} = {{ nominal = 1 }}" for i in range(1, coordinates + 1))
    path.write_text(f'[model]\ncoordinates = {names!r}\ninputs = ["u"]\n'
                    f'equations = [{equations}]\n[parameters]\n{parameters}\n{extra_parameter}')
    return path


@pytest.mark.parametrize(("case", "message"), [
    ("name_clash", "would share the names m1_std"),
    ("out_is_a_file", "is not a folder"),
    ("homogeneous", "only up to a common scale"),
])
def test_what_the_fmu_cannot_be_built_for_is_refused(tmp_path, capsys, case, message):
    out = tmp_path / "out"
    if case == "name_clash":
        model = tmp_path / "m.toml"
        model.write_text('[model]\ncoordinates = ["q"]\ninputs = ["u"]\n'
                         'equations = ["m1*der(q,2) + m1_std*der(q) = u"]\n'
                         '[parameters]\nm1 = { nominal = 1 }\nm1_std = { nominal = 0 }\n')
    elif case == "homogeneous":  # no input: the unknowns only up to a scale
        model = tmp_path / "m.toml"
        model.write_text('[model]\ncoordinates = ["q"]\n'
                         'equations = ["J*der(q,2) + c*der(q) + k*q = 0"]\n'
                         '[parameters]\nJ = { nominal = 1 }\nc = { nominal = 0.1 }\n'
                         'k = { nominal = 10 }\n')
    else:
        model = write_model(tmp_path / "m.toml", 1)
        out.write_text("a file")
    assert main(["fmu", "--model", str(model), "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert case == "out_is_a_file" or not (out / "m.fmu").exists()


def test_the_fmus_physical_values_do_not_depend_on_the_files_units(tmp_path, emps_fmus):
    """x in mm, Fv in kN.s/m, Fc and OF in kN: the same physical values as in SI (the
    observer's gain bound follows the coordinate's unit; the identifier works in SI).
    Measured: equal to 1e-15 relative."""
    text = (EMPS / "emps.toml").read_text()
    for old, new in (('x = "m"', 'x = "mm"'), ('unit = "N.s/m"', 'unit = "kN.s/m"'),
                     ('Fc = { nominal = 0, unit = "N" }', 'Fc = { nominal = 0, unit = "kN" }'),
                     ('OF = { nominal = 0, unit = "N" }', 'OF = { nominal = 0, unit = "kN" }')):
        assert old in text
        text = text.replace(old, new)
    (tmp_path / "emps.toml").write_text(text)
    scaled = export(tmp_path / "emps.toml", tmp_path / "out")
    model = read_model(EMPS / "emps.toml")
    log = read_log(EMPS / "data" / "DATA_EMPS.mat", model)
    names = [p.name for p in model.parameters]
    si = run_log(emps_fmus[2], log.t, {"x": log.q[:, 0]}, {"vir": log.inputs[:, 0]}, names)
    other = run_log(scaled, log.t, {"x": 1000.0 * log.q[:, 0]}, {"vir": log.inputs[:, 0]}, names)
    for name, factor in (("M", 1.0), ("Fv", 1e3), ("Fc", 1e3), ("OF", 1e3)):
        assert abs(factor * other[name][-1] - si[name][-1]) <= 1e-3 * abs(si[name][-1]), name


@pytest.mark.parametrize("version", [2, 3])
def test_the_estimates_do_not_depend_on_the_communication_step(tmp_path, version):
    """The same inputs (held over 10 internal steps) at communication steps of h, 2 h, 5 h
    and 10 h, FMI 2 and 3: every output at the common communication points is the same
    number (the statistics and the inputs' cadence follow the internal steps, not the
    importer's communication points)."""
    fmu = export(TWO_MASS, tmp_path, "--fmi-version", str(version))
    t, x1, x2, F = two_mass_log(seconds=6.0)
    held = (np.arange(len(t)) // 10) * 10  # each input held over 10 internal steps
    signals = np.zeros(len(t), dtype=[("time", float), ("x1", float), ("x2", float),
                                      ("F", float)])
    signals["time"], signals["x1"], signals["x2"], signals["F"] = t, x1[held], x2[held], F[held]
    h = float(t[1] - t[0])
    names = list(TRUTH)
    outputs = names + [f"{n}_std" for n in names] + [
        "observer.input_hold", "observer.coarse_inputs", "observer.excitation",
        "observer.negative_damping", "observer.parameters_held"]
    runs = [fmpy.simulate_fmu(str(fmu), stop_time=float(t[-1]) - 10 * h, input=signals,
                              output_interval=ratio * h, start_values={"observer.h": h},
                              output=outputs) for ratio in (1, 2, 5, 10)]
    fine, coarsest = runs[0], runs[-1]
    assert len(coarsest) > 500 and np.any(coarsest[names[0]] != TRUTH[names[0]])
    # the staircase of 10 steps is seen, whatever the communication step
    assert coarsest["observer.coarse_inputs"][-1]
    assert coarsest["observer.input_hold"][-1] == pytest.approx(10 * h)
    row = {round(time / h): k for k, time in enumerate(fine["time"])}
    for coarse in runs[1:]:
        common = [row[round(time / h)] for time in coarse["time"]]  # the same instants
        for name in outputs:
            assert np.array_equal(fine[name][common], coarse[name]), name


def test_a_communication_step_coarser_than_the_log_is_reported(emps_fmus, capfd):
    """fmpy without --output-interval feeds the EMPS log every 40th sample (its default
    interval, the stop time / 500): the FMU says so in ``observer.coarse_inputs``, with the
    hold in ``observer.input_hold`` and a warning through the FMI logger; fed every sample
    it says nothing."""
    model = read_model(EMPS / "emps.toml")
    log = read_log(EMPS / "data" / "DATA_EMPS.mat", model)
    seconds = 6.0
    keep = log.t - log.t[0] <= seconds
    step = float(log.t[1] - log.t[0])
    signals = np.zeros(int(keep.sum()), dtype=[("time", float), ("x", float), ("vir", float)])
    signals["time"], signals["x"] = log.t[keep] - log.t[0], log.q[keep, 0]
    signals["vir"] = log.inputs[keep, 0]
    outputs = ["observer.coarse_inputs", "observer.input_hold"]
    for interval, coarse in ((step, False), (40 * step, True)):
        # fmpy's own logger prints the FMU's messages (a logger= of simulate_fmu replaces
        # the one native proxy every fmpy instance shares, and dangles once it returns)
        result = fmpy.simulate_fmu(str(emps_fmus[2]), stop_time=seconds, step_size=step,
                                   output_interval=interval, input=signals,
                                   start_values={"observer.h": step}, output=outputs)
        messages = capfd.readouterr().out.splitlines()
        assert bool(result["observer.coarse_inputs"][-1]) == coarse, interval
        held = result["observer.input_hold"][-1]
        assert held == pytest.approx(interval, rel=1e-6), (interval, held)
        warned = [m for m in messages if "staircase" in m]
        assert (len(warned) == 1) == coarse, messages
        if coarse:
            assert f"--output-interval {step:g}" in warned[0]
            assert "40 internal steps" in warned[0]
