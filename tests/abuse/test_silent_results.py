"""Inputs that used to give a silent wrong result, a file no reader takes or a warning
with exit status 0: names the generated code shares with the file, an unknown that
cancels out, estimates that are not finite, robot roles and joint terms given wrongly,
non-strict JSON, names with newlines and control characters copied into generated files,
and warnings of the robot path.  Each is refused by name (exit status 2), escaped, or
said and counted (exit status 1)."""
from __future__ import annotations

import json
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from cli_runner import cli, refused

pytestmark = pytest.mark.cli

MODEL = '''[model]
coordinates = ["{c}"]
inputs = ["F"]
equations = ["{eq}"]

[parameters]
M = {{ nominal = 1 }}
Fv = {{ nominal = 1 }}
{extra}'''


def model(path: Path, eq: str = "M*der(x,2) + Fv*der(x) = F", c: str = "x",
          extra: str = "") -> Path:
    path.write_text(MODEL.format(c=c, eq=eq, extra=extra), encoding="utf-8")
    return path


def mass_log(path: Path, scale: float = 1.0, seconds: float = 8.0) -> Path:
    """x of M x'' + Fv x' = F (M = 2, Fv = 0.7) driven by two sines; F times ``scale``."""
    t = np.arange(0.0, seconds, 1e-3)
    force = np.sin(2 * np.pi * 0.5 * t) + 0.5 * np.sin(2 * np.pi * 1.3 * t)
    x, v = np.zeros_like(t), 0.0
    for k in range(1, len(t)):
        v += (force[k - 1] - 0.7 * v) / 2.0 * 1e-3
        x[k] = x[k - 1] + v * 1e-3
    np.savetxt(path, np.column_stack([t, x, force * scale]), delimiter=",", header="t,x,F",
               comments="", fmt="%.17g")
    return path


@pytest.mark.parametrize("name", ["e", "theta_0", "E", "x0"])
def test_the_simulations_generated_code_names_never_collide_with_the_files(tmp_path, name):
    """The simulation's compiled function (scores, cross-validation, output error) means
    the coordinate by the coordinate's name and Euler's number by exp(1)."""
    from harness.model import read_model
    from harness.model.simulation import Dynamics

    eq = "M*der({c},2) + Fv*exp(1)*der({c}) + atan({c}) = F"
    ours = Dynamics(read_model(model(tmp_path / "a.toml", eq.format(c=name), c=name)))
    plain = Dynamics(read_model(model(tmp_path / "b.toml", eq.format(c="y"), c="y")))
    rng = np.random.default_rng(2)
    q, qd, u = (rng.normal(size=(20, 1)) for _ in range(3))
    theta = np.array([2.0, 0.7])
    assert np.array_equal(ours(q, qd, u, theta), plain(q, qd, u, theta))


@pytest.mark.parametrize("term", ["K*(sin(x)^2 + cos(x)^2 - 1)", "K*(cosh(x)^2 - sinh(x)^2 - 1)",
                                  "K*((x+1)^2 - x^2 - 2*x - 1)*der(x)"])
def test_an_unknown_whose_term_is_identically_zero_is_refused_by_name(tmp_path, term):
    path = model(tmp_path / "m.toml", f"M*der(x,2) + Fv*der(x) + {term} = F",
                 extra="K = { nominal = 1 }\n")
    code, text = cli(["fmu", "--model", str(path), "--out", str(tmp_path / "out")])
    assert code == 2, text
    refused(code, text, str(path), "K", "cancel out")


def test_a_term_that_is_nearly_but_not_zero_is_kept(tmp_path):
    from harness.model import read_model
    read_model(model(tmp_path / "m.toml", "M*der(x,2) + Fv*der(x) + "
                     "K*(sin(x)^2 + cos(x)^2 - 0.999999) = F", extra="K = { nominal = 1 }\n"))


def test_estimates_that_are_not_finite_are_an_error_not_a_file(tmp_path):
    """A force column 1e200 times too large: the least squares' errors overflow."""
    path = model(tmp_path / "m.toml")
    out = tmp_path / "out"
    code, text = cli(["identify", str(mass_log(tmp_path / "log.csv", 1e200)), "--model",
                      str(path), "--out", str(out), "--refine", "none"])
    assert code == 2, text
    refused(code, text, "log.csv", "not a finite number", "scaling")
    assert not (out / "parameters.csv").exists()


def test_a_column_so_large_that_the_equations_overflow_is_named(tmp_path):
    """A force column 1e307 times too large: the filtered log overflows; the refusal names
    the column and its size, and no numpy warning reaches the user."""
    path = model(tmp_path / "m.toml")
    code, text = cli(["identify", str(mass_log(tmp_path / "log.csv", 1e307)), "--model",
                      str(path), "--out", str(tmp_path / "out"), "--refine", "none"])
    refused(code, text, "log.csv", "overflow", "'F'", "unit or scale")
    assert "RuntimeWarning" not in text


def test_robot_columns_name_only_the_robots_roles(tmp_path):
    from harness.robot.examples import example_urdf
    urdf, _ = example_urdf("double_pendulum")
    t = np.arange(3000) * 1e-3
    np.savetxt(tmp_path / "log.csv", np.column_stack([t, np.sin(t), np.cos(t), t, t]),
               delimiter=",", header="t,q1,q2,u1,u2", comments="")
    for command in ("identify", "validate"):
        code, text = cli([command, str(tmp_path / "log.csv"), "--robot", str(urdf), "--out",
                          str(tmp_path / command), "--columns", "q3=q1"])
        assert code == 2, text
        refused(code, text, "'q3'", "roles: t, q1, q2, u1, u2")


def test_a_joint_term_given_twice_is_refused_naming_the_joint(tmp_path):
    from harness.robot.joint_terms import JointTermsError, read_sidecar
    path = tmp_path / "joint_terms.csv"
    path.write_text("joint,term,value,std_error,unit\nj1,offset,0.1,0,rad\nj2,offset,0.2,0,rad\n"
                    "j1,offset,0.3,0,rad\n")
    with pytest.raises(JointTermsError, match="joint 'j1' has a second offset"):
        read_sidecar(path, ["j1", "j2"])


def test_every_json_written_is_strict_and_non_finite_figures_are_named(tmp_path, caplog):
    from harness.json_files import strict_json, write_json
    from harness.robot.validate import write_validation

    text, nulls = strict_json({"a": [1.0, float("nan")], "b": {"c": float("inf")}})
    assert json.loads(text, parse_constant=pytest.fail) == {"a": [1.0, None], "b": {"c": None}}
    assert nulls == ["a[1] (nan)", "b.c (inf)"]
    write_json(tmp_path / "x.json", {"pooled": float("-inf")})
    assert "pooled (-inf)" in caplog.text
    t = np.arange(20.0)
    write_validation(tmp_path, "r.urdf", "log.csv", 0.1, t, np.ones((20, 1)),
                     np.full((20, 1), 1e308), {"j1": float("inf")}, float("inf"))
    data = json.loads((tmp_path / "validation.json").read_text(), parse_constant=pytest.fail)
    assert data["relative_error"] == {"per_joint": {"j1": None}, "pooled": None}
    assert "relative_error.pooled (inf)" in caplog.text


@pytest.mark.parametrize("name", ["m\nsizes 7 7 7\n.toml", "m\x01\x1b[31m.toml", "m\u2028.toml"])
def test_a_model_file_name_with_newlines_or_controls_makes_a_readable_fmu(tmp_path, name):
    from lxml import etree

    from harness.model.program import evaluate_program
    path = model(tmp_path / name)
    code, text = cli(["fmu", "--model", str(path), "--out", str(tmp_path / "out")])
    assert code == 0, text
    fmu = next((tmp_path / "out").glob("*.fmu"))
    with zipfile.ZipFile(fmu) as archive:
        program = archive.read("resources/model.txt").decode()
        description = etree.fromstring(archive.read("modelDescription.xml"))
    assert program.splitlines()[2] == "sizes 1 1 2"  # the name stays on its comment line
    Y, r = evaluate_program(program, *(np.ones((3, 1)) for _ in range(4)))  # the C parser
    assert Y.shape == (3, 1, 2)
    assert "\n" not in description.get("modelName")


def test_a_log_name_with_toml_in_it_stays_in_the_comment(tmp_path):
    """identified.toml's header names the files: a newline there would start TOML."""
    from harness.model import parse_model, read_model
    from harness.model.writer import model_toml
    path = model(tmp_path / "m.toml", extra='[units]\nx = "m"\nF = "N"\n')
    path.write_text(path.read_text().replace("M = { nominal = 1 }", 'M = { nominal = 1, unit = "kg" }')
                    .replace("Fv = { nominal = 1 }", 'Fv = { nominal = 1, unit = "kg/s" }'))
    source = read_model(path)
    text = model_toml(source, [2.0, 0.7], header=['m.toml identified from log\n[units]\n'
                                                  'x = "mm"\n\x7f.csv'])
    back = parse_model(text)
    assert back.units == source.units and back.nominal.tolist() == [2.0, 0.7]
    assert text.splitlines()[0].startswith("# m.toml identified from log\\n[units]")


def test_the_mean_step_of_extreme_times_does_not_overflow():
    from harness.log_columns import mean_step
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert mean_step(np.array([-1.7e308, 0.0, 1.7e308])) == 1.7e308
        assert mean_step(np.array([-1.7e308, 1.7e308])) == np.inf


def test_identify_robot_exits_1_after_its_warnings(tmp_path, monkeypatch):
    """A result with warnings (the identified model predicts worse than the URDF) is
    written, said, and exits 1 as docs/cli.md says."""
    from harness.robot.examples import example_urdf
    from harness.robot.pipeline import Identification
    urdf, _ = example_urdf("double_pendulum")
    t = np.arange(6000) * 1e-3
    q = np.column_stack([0.8 * np.sin(1.3 * t), 0.6 * np.sin(2.1 * t)])
    u = np.column_stack([5.0 * np.sin(1.3 * t), 2.0 * np.cos(2.1 * t)])
    np.savetxt(tmp_path / "log.csv", np.column_stack([t, q, u]), delimiter=",",
               header="t,q1,q2,u1,u2", comments="", fmt="%.17g")
    monkeypatch.setattr(Identification, "warnings",
                        property(lambda self: ["the identified model predicts worse"]))
    code, text = cli(["identify", str(tmp_path / "log.csv"), "--robot", str(urdf), "--out",
                      str(tmp_path / "out"), "--unknown", "payload"])
    assert code == 1, text
    assert "the identified model predicts worse" in text
