"""The two-link arm with a passive joint (bench/cases/two_link.py) identified by the robot
path, the model-file path and the practitioner's least squares, in one run.

    .venv/bin/python -m bench.reports.two_link_paths [--quick] [--out FILE.md] [--keep DIR]

--out (default build/reports/two_link_paths.md) receives the generated document: the
command, date, commit and load average, the figures of each path and whether the two
paths agree within 1 %.  Edit this script, not the document.

One training log (40 s; --quick: 12 s) and one validation log (another seed, half as long;
--quick: 8 s, the shortest validate --model takes), written as CSV with their jittering
clock.  On the training log:
  robot  `identify LOG --robot URDF` (the real CLI, a subprocess): its base-parameter
         estimate (parameters.csv) and its identified.urdf;
  model  `identify LOG --model two_link.toml` (the real CLI): parameters.csv;
  LS     the practitioner's least squares (robot_real_logs.least_squares_baseline:
         Butterworth filtfilt at 10 Hz of q and u, central differences, np.linalg.lstsq
         on the same base regressor), on the log resampled onto its mean step.
Every estimate is expressed in the model file's parameters (the robot path's base
parameters are the same combinations; the bench checks the mapping on random states).

Scores on the validation log:
  true states  the independent scorer: joint 1's torque predicted by the estimate at the
               validation run's true q, q', q'' (known from the simulation; plain numpy,
               two_link.regressor) against the true torque, RMS error over RMS torque;
               joint 2's predicted torque (true: 0) as its RMS in N.m; pooled: |error| /
               |torque| over both joints.  No filter, no encoder, no window: shares none
               of the paths' choices.
  validate     the commands' own figures: `validate --robot identified.urdf` (joint 1 and
               pooled) and `validate --model` with each estimate written into the model
               file (equation 1 and the full-rate reconstruction).
The diagnosis table refits the model file's regressor on the training log under the
robot path's choices and the model path's, one at a time (derivative pipeline, friction
rows, equation weighting) and scores each fit on the true states."""
from __future__ import annotations

import argparse
import csv
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from bench.cases import two_link
from bench.reports import REPORTS, commit
from bench.reports.robot_real_logs import _regressor, least_squares_baseline, resample
from harness.model import read_model
from harness.model.friction_rows import joint_friction_rows
from harness.model.log import read_log as read_model_log
from harness.model.scores import PieceSimulator, parts_for
from harness.model.selection import CrossValidation
from harness.model.simulation import Dynamics
from harness.model.zero_phase import ZeroPhase, regression
from harness.robot.base_parameters import base_parameters
from harness.robot.joint_log import JointLog
from harness.robot.native import core_defaults
from harness.robot.smoothing import savitzky_golay
from harness.robot.urdf import read_urdf

REPO = Path(__file__).resolve().parents[2]
AGREE = 0.01  # the two paths' figures agree within 1 % (relative)
# the robot path's base parameters (parameters.csv) and the model file's
ROBOT_NAMES = {"joint1.Ixx": "ZZ1R", "joint1.my": "MY1", "joint1.mz": "MZ1R",
               "joint2.Ixx": "ZZ2", "joint2.my": "MY2", "joint2.mz": "MZ2",
               "joint1.fv": "fv1", "joint1.fc": "fc1", "joint2.fv": "fv2", "joint2.fc": "fc2"}


# --- the commands ---------------------------------------------------------------------------

def run(*arguments: str) -> dict:
    """`python -m harness ARGUMENTS` in a subprocess: exit status, wall time, stderr."""
    command = [sys.executable, "-m", "harness", *arguments]
    started = time.perf_counter()
    done = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
    return {"rc": done.returncode, "seconds": time.perf_counter() - started,
            "stdout": done.stdout, "stderr": done.stderr.strip(),
            "command": shlex.join(["python", "-m", "harness", *arguments]).replace(
                f"{REPO}/", "")}


def _checked(ran: dict) -> dict:
    if ran["rc"] not in (0, 1):
        raise RuntimeError(f"{ran['command']} exited {ran['rc']}: {ran['stderr']}")
    return ran


def read_csv_values(path: Path, name: str, value: str) -> dict[str, float]:
    with path.open() as handle:
        return {row[name]: float(row[value]) for row in csv.DictReader(handle)}


def robot_mapping(robot) -> tuple[list[int], list[str]]:  # noqa: ANN001
    """The robot path's base parameters in the model file's order (indices into base's
    names), checked: the base regressor equals the model file's columns on random states."""
    body = robot.rigid_body()
    base = base_parameters(body, robot.arrays()["types"], robot.joint_names, "all")
    names = list(base.names)
    order = [names.index(r) for m in two_link.NAMES for r, mm in ROBOT_NAMES.items() if mm == m]
    rng = np.random.default_rng(7)
    q, qd, qdd = (rng.uniform(-a, a, (50, 2)) for a in (np.pi, 4.0, 20.0))
    Y = _regressor(body, base, q, qd, qdd)[:, :, order]
    if not np.allclose(Y, two_link.regressor(q, qd, qdd), rtol=1e-9, atol=1e-12):
        raise RuntimeError("the robot's base regressor is not the model file's")
    return order, names


def with_values(theta: np.ndarray, path: Path) -> Path:
    """The model file with `theta` as its nominal values (what validate --model scores)."""
    path.write_text(two_link.model_toml(theta), encoding="utf-8")
    return path


# --- the scores -----------------------------------------------------------------------------

def positive_definite(theta: np.ndarray) -> bool:
    """Whether the inertia matrix M(q) of `theta` is positive definite at every q: ZZ2 > 0
    and det M = ZZ1R ZZ2 - l^2 (MZ2 cos q2 + MY2 sin q2)^2 > 0 for every q2."""
    t = dict(zip(two_link.NAMES, theta))
    return bool(t["ZZ2"] > 0 and t["ZZ1R"] * t["ZZ2"]
                > two_link.LENGTH ** 2 * (t["MZ2"] ** 2 + t["MY2"] ** 2))


def true_state_scores(theta: np.ndarray, check: two_link.Run) -> dict:
    """The independent scorer: torques at the validation run's true states."""
    predicted = two_link.regressor(check.q_true, check.qd_true, check.qdd_true) @ theta
    error = predicted - check.tau_true
    tau1 = check.tau_true[:, 0]
    return {"joint1": float(np.sqrt(np.mean(error[:, 0] ** 2)) / np.sqrt(np.mean(tau1 ** 2))),
            "joint2_Nm": float(np.sqrt(np.mean(error[:, 1] ** 2))),
            "pooled": float(np.linalg.norm(error) / np.linalg.norm(check.tau_true))}


def validate_model(theta: np.ndarray, data: Path, folder: Path) -> dict:
    """validate --model's equation-1 figures for the model file holding `theta`: through
    its zero-phase pipeline and at the full rate (raw central differences)."""
    folder.mkdir(parents=True, exist_ok=True)
    ran = _checked(run("validate", str(data), "--model",
                       str(with_values(theta, folder / "arm.toml")), "--out",
                       str(folder / "out")))
    got = json.loads((folder / "out" / "validation.json").read_text())
    return {"pipeline": got["relative_error"]["per_equation"][0],
            "full_rate": got["reconstruction_error"]["per_equation"][0],
            "seconds": ran["seconds"]}


def validate_robot(urdf: Path, data: Path, folder: Path) -> dict:
    """validate --robot's figures (joint 1, pooled) for a URDF."""
    ran = _checked(run("validate", str(data), "--robot", str(urdf), "--out", str(folder)))
    got = json.loads((folder / "validation.json").read_text())["relative_error"]
    return {"joint1": got["per_joint"]["joint1"], "pooled": got["pooled"],
            "seconds": ran["seconds"]}


# --- the diagnosis: the model file's regression under each path's choices ------------------

def diagnosis(train: Path, model_out: Path, robot_out: Path, check: two_link.Run
              ) -> list[dict]:
    """The model file's regressor fitted on the training log under the derivative
    pipelines of both paths and the practitioner's, with and without the robot path's
    friction rows (each joint's equation left out within a window of its velocity
    reversals and below the core's min_speed), by plain least squares or weighting each
    equation by 1 / its residual RMS (both paths' two passes); each scored on the
    validation run's true states (joint 1)."""
    model = read_model(model_out / "identified.toml")
    log = read_model_log(train, model)       # resampled as the model path does
    joint_log = JointLog(log.t, log.q, log.inputs)
    chosen = json.loads((model_out / "identification.json").read_text())["pipeline_choice"]
    c = chosen["chosen"]
    window = json.loads((robot_out / "summary.json").read_text())["regression_window_s"]
    pipelines = {
        f"model path's: {c['differentiator']}, {c['cutoff_hz']:.3g} Hz, decimated by "
        f"{c['decimation']}": ZeroPhase.for_step(log.step, c["cutoff_hz"], c["decimation"],
                                                 c["differentiator"]),
        "Butterworth 10 Hz, central differences": ZeroPhase.for_step(log.step, 10.0, 1),
        f"robot path's: Savitzky-Golay {window:.3g} s": None}
    min_speed = core_defaults().min_speed
    rows = []
    for label, settings in pipelines.items():
        if settings is None:
            # identify_robot's rows: from 0.5 s to a window before the end
            used = np.arange(round(0.5 / log.step), log.samples - round(window / log.step) - 1)
            q, qd, qdd, u = savitzky_golay(joint_log, window, at=used)
            Y, r, margin = two_link.regressor(q, qd, qdd), u, window
            speed = savitzky_golay(joint_log, window)[1]
        else:
            fit_rows = regression(model, log, settings)
            Y, r = fit_rows.Y, fit_rows.r
            used = np.round((fit_rows.t - log.t[0]) / log.step).astype(int)
            margin = max(settings.border * log.step / 5.0, log.step)  # one cut-off period
            speed = np.gradient(settings.low_pass(log.q), log.step, axis=0)
        mask = np.column_stack([joint_friction_rows(speed[:, i], log.step, margin, min_speed,
                                                    at=used) for i in range(2)])
        for masked in (False, True):
            for weighted in (False, True):
                theta = weighted_least_squares(Y, r, mask if masked else np.ones_like(mask),
                                               weighted)
                rows.append({"pipeline": label, "friction rows": masked, "weighted": weighted,
                             "kept": mask.mean(axis=0).tolist() if masked else [1.0, 1.0],
                             "theta": theta.tolist(), "definite": positive_definite(theta),
                             "joint1": true_state_scores(theta, check)["joint1"]})
    for row, error in zip(rows, run_errors(model, log, [np.array(r["theta"]) for r in rows])):
        row["runs"] = error
    return rows


def weighted_least_squares(Y: np.ndarray, r: np.ndarray, mask: np.ndarray,
                           weighted: bool) -> np.ndarray:
    """Least squares over the rows `mask` keeps (rows, equations); `weighted`: a second
    pass with each equation divided by its residual RMS from the first (both paths'
    weighting)."""
    scale = np.ones(Y.shape[1])
    for _ in range(2 if weighted else 1):
        A = (Y * (mask / scale)[:, :, None]).reshape(-1, Y.shape[2])
        theta = np.linalg.lstsq(A, (r * mask / scale).ravel(), rcond=None)[0]
        residual = (r - Y @ theta) * mask
        rms = np.sqrt(np.sum(residual ** 2, axis=0) / np.maximum(mask.sum(axis=0), 1))
        scale = np.maximum(rms, 1e-9 * rms.max())
    return theta


def run_errors(model, log, thetas: list[np.ndarray]) -> list[float]:  # noqa: ANN001
    """The model path's own selection score for each parameter vector, on the whole
    training log (not held out): its cross-validation's short simulation runs from the
    measured state (initial state fitted), RMS position error relative to the motion,
    pooled over the coordinates."""
    cv, dynamics = CrossValidation(model, log), Dynamics(model)
    out = []
    for theta in thetas:
        try:
            parts = parts_for(dynamics, log, theta)
        except (FloatingPointError, ValueError):
            parts = 1
        with np.errstate(all="ignore"):
            error = PieceSimulator(dynamics, log, cv.runs, parts).error(theta)
        out.append(error if np.isfinite(error) else float("inf"))
    return out


# --- one run ----------------------------------------------------------------------------------

def bench(train_seconds: float, check_seconds: float, work: Path) -> dict:
    robot, urdf = two_link.robot()
    started = time.perf_counter()
    training = two_link.simulate(train_seconds, two_link.TRAIN_SEED)
    check = two_link.simulate(check_seconds, two_link.VALIDATION_SEED)
    simulated = time.perf_counter() - started
    train, data, toml = work / "train.csv", work / "validation.csv", work / "two_link.toml"
    two_link.write(training, train, toml)
    two_link.write(check, data)
    order, names = robot_mapping(robot)
    robot_run = _checked(run("identify", str(train), "--robot", str(urdf), "--out",
                             str(work / "robot")))
    model_run = _checked(run("identify", str(train), "--model", str(toml), "--out",
                             str(work / "model")))
    started = time.perf_counter()
    even = JointLog(*resample(training.t, training.q, training.u))
    base = base_parameters(robot.rigid_body(), robot.arrays()["types"], robot.joint_names, "all")
    ls = least_squares_baseline(robot, base, even)[order]
    ls_seconds = time.perf_counter() - started
    estimate = read_csv_values(work / "robot" / "parameters.csv", "parameter", "estimate")
    identified = read_urdf(work / "robot" / "identified.urdf").arrays()
    values = read_csv_values(work / "model" / "parameters.csv", "name", "value")
    thetas = {"robot": np.array([estimate[n] for n in np.array(names)[order]]),
              "robot_urdf": two_link.base_values(identified["link"], identified["friction"]),
              "model": np.array([values[n] for n in two_link.NAMES]),
              "ls": ls}
    link, friction = two_link.truth()
    truth = two_link.base_values(link, friction)
    paths: dict = {}
    for key, theta in {**thetas, "truth": truth}.items():
        paths[key] = {"theta": theta.tolist(), "true_states": true_state_scores(theta, check),
                      "validate_model": validate_model(theta, data, work / f"validate_{key}")}
    paths["robot_urdf"]["validate_robot"] = validate_robot(
        work / "robot" / "identified.urdf", data, work / "validate_robot")
    summary = json.loads((work / "robot" / "summary.json").read_text())
    choice = json.loads((work / "model" / "identification.json").read_text())
    return {"samples": len(training.t), "validation_samples": len(check.t),
            "simulation_s": simulated, "truth": truth.tolist(), "paths": paths,
            "commands": {"robot": robot_run, "model": model_run},
            "ls_seconds": ls_seconds,
            "robot_window_s": summary.get("regression_window_s"),
            "model_pipeline": choice["pipeline_choice"], "model_method": choice["method"],
            "diagnosis": diagnosis(train, work / "model", work / "robot", check)}


# --- the document -----------------------------------------------------------------------------

def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.2f} %"


def _figure(x: float | None) -> str:
    return "n/a" if x is None else f"{x:.3g}"


def _agree(a: float, b: float) -> str:
    gap = abs(a - b) / min(abs(a), abs(b))
    return f"{100 * gap:.1f} % apart: " + ("yes" if gap <= AGREE else "**NO**")


LABELS = {"robot": "robot path: estimate (parameters.csv)",
          "robot_urdf": "robot path: identified.urdf",
          "model": "model path (parameters.csv)",
          "ls": "least squares (Butterworth 10 Hz + central differences + lstsq)",
          "truth": "truth (the simulation's; sign(q') friction)"}


def document(run_: dict) -> str:
    r = run_["result"]
    p = r["paths"]
    cmd = r["commands"]
    lines = [
        "# The two-link arm with a passive joint: robot path, model path, least squares",
        "",
        "Generated by `bench/reports/two_link_paths.py` (edit the script, not this file).",
        "",
        f"- command: `{run_['command']}`",
        f"- date: {run_['date']} (UTC), commit {run_['commit']}",
        f"- load average (1 min) at start {run_['load_start']:.2f}, at end "
        f"{run_['load_end']:.2f} (2 cores, shared); run time {run_['runtime_s']:.0f} s "
        f"(simulation {r['simulation_s']:.0f} s)",
        f"- training log {run_['train_s']:g} s ({r['samples']} samples), validation log "
        f"{run_['check_s']:g} s ({r['validation_samples']} samples, another seed): 200 Hz "
        "+-10 % clock jitter, joint 2 passive, 0.01 rad encoder steps",
        f"- identify --robot: exit {cmd['robot']['rc']}, {cmd['robot']['seconds']:.1f} s, "
        f"regression window {r['robot_window_s']:.3g} s; identify --model: exit "
        f"{cmd['model']['rc']}, {cmd['model']['seconds']:.1f} s, "
        f"{r['model_pipeline']['chosen']['differentiator']} derivatives at "
        f"{r['model_pipeline']['chosen']['cutoff_hz']:.3g} Hz, decimation "
        f"{r['model_pipeline']['chosen']['decimation']}, {r['model_method']}; "
        f"least squares {r['ls_seconds']:.2f} s",
        "- the model path's candidates (blocked cross-validation: relative simulation "
        "error, input error relative to the reference pipeline's, their product relative "
        "to the best): " + "; ".join(
            f"{c['label']} {_pct(c['score'])}, {_figure(c.get('input_score'))}, "
            f"{_figure(c.get('combined'))}" for c in r["model_pipeline"]["candidates"]),
        "",
        "Validation log. True states: the independent scorer (each estimate's torques at the "
        "run's true q, q', q''; joint 1: RMS error over RMS torque; joint 2, whose torque is "
        "0: RMS of the predicted torque; pooled: over both joints). validate --model: each "
        "estimate written into the model file, equation 1 through validate's zero-phase "
        "pipeline and at the full rate (raw central differences). validate --robot: "
        "identified.urdf only.",
        "",
        "| method | true states: joint 1 | joint 2 [N.m] | pooled | validate --model: eq. 1 "
        "(pipeline) | eq. 1 (full rate) | validate --robot: joint 1 | pooled | M(q) positive "
        "definite |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for key, label in LABELS.items():
        s, v = p[key]["true_states"], p[key]["validate_model"]
        vr = p[key].get("validate_robot")
        lines.append(f"| {label} | {_pct(s['joint1'])} | {s['joint2_Nm']:.4f} | "
                     f"{_pct(s['pooled'])} | {_pct(v['pipeline'])} | {_pct(v['full_rate'])} | "
                     + (f"{_pct(vr['joint1'])} | {_pct(vr['pooled'])} | " if vr else "- | - | ")
                     + ("yes" if positive_definite(np.array(p[key]["theta"])) else "no") + " |")
    a, b = p["robot"], p["model"]
    lines += [
        "", "## Do the robot path and the model path agree within 1 %?", "",
        f"- true states, joint 1: {_pct(a['true_states']['joint1'])} against "
        f"{_pct(b['true_states']['joint1'])}, "
        f"{_agree(a['true_states']['joint1'], b['true_states']['joint1'])}",
        f"- true states, pooled: {_pct(a['true_states']['pooled'])} against "
        f"{_pct(b['true_states']['pooled'])}, "
        f"{_agree(a['true_states']['pooled'], b['true_states']['pooled'])}",
        f"- validate --model, equation 1: {_pct(a['validate_model']['pipeline'])} against "
        f"{_pct(b['validate_model']['pipeline'])}, "
        f"{_agree(a['validate_model']['pipeline'], b['validate_model']['pipeline'])}",
        "", "## The parameters", "",
        "| parameter | truth | " + " | ".join(LABELS[k] for k in ("robot", "robot_urdf",
                                                                  "model", "ls")) + " |",
        "|---|---|---|---|---|---|"]
    for i, name in enumerate(two_link.NAMES):
        lines.append(f"| {name} | {r['truth'][i]:.4g} | " + " | ".join(
            f"{p[k]['theta'][i]:.4g}" for k in ("robot", "robot_urdf", "model", "ls")) + " |")
    lines += ["", "## Diagnosis: the model file's regression under each path's choices", "",
              "The model file's regressor fitted on the training log (resampled as the model "
              "path does) by each derivative pipeline, with or without the robot path's "
              "friction rows (a joint's equation left out within the pipeline's window of a "
              "reversal of its velocity and below the core's min_speed), by plain least "
              "squares or with each equation weighted by 1 / its residual RMS after an "
              "unweighted pass (what both paths do). M(q) positive definite: at every q2. "
              "The selection score: the model path's cross-validation scorer (0.2 s "
              "simulation runs from the measured state, relative position error) applied to "
              "the fit on the whole training log (in-sample; the model path scores each "
              "candidate out of sample, on held-out blocks). True states: joint 1's error on "
              "the validation run.", "",
              "| pipeline | friction rows | equations weighted | rows kept (joint 1, 2) | "
              "ZZ1R | MZ1R | ZZ2 | MZ2 | M(q) positive definite | the model path's selection "
              "score (training log) | true states: joint 1 |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for d in r["diagnosis"]:
        t = dict(zip(two_link.NAMES, d["theta"]))
        lines.append(f"| {d['pipeline']} | {'robot path' if d['friction rows'] else 'all'} | "
                     f"{'yes' if d['weighted'] else 'no'} | "
                     f"{100 * d['kept'][0]:.0f} %, {100 * d['kept'][1]:.0f} % | "
                     f"{t['ZZ1R']:.4g} | {t['MZ1R']:.4g} | {t['ZZ2']:.4g} | {t['MZ2']:.4g} | "
                     f"{'yes' if d['definite'] else 'no'} | {_pct(d['runs'])} | "
                     f"{_pct(d['joint1'])} |")
    lines += ["", "Commands (the logs written by the bench):", "",
              f"- `{cmd['robot']['command']}`", f"- `{cmd['model']['command']}`", ""]
    for key in ("robot", "model"):
        if cmd[key]["stderr"]:
            lines += [f"identify --{key} stderr:", "", "```", cmd[key]["stderr"], "```", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="a 12 s training log and an 8 s validation log (about 3 minutes)")
    parser.add_argument("--out", type=Path, default=REPORTS / "two_link_paths.md",
                        help="the generated document (default %(default)s)")
    parser.add_argument("--keep", type=Path, default=None,
                        help="keep the logs and the commands' outputs in this folder")
    args = parser.parse_args(argv)
    train_s, check_s = (12.0, 8.0) if args.quick else (40.0, 20.0)
    run_: dict = {"command": shlex.join(["python", "-m", "bench.reports.two_link_paths",
                                         *(sys.argv[1:] if argv is None else argv)]),
                  "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M"),
                  "commit": commit(), "train_s": train_s, "check_s": check_s,
                  "load_start": os.getloadavg()[0]}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as temporary:
        work = args.keep or Path(temporary)
        work.mkdir(parents=True, exist_ok=True)
        run_["result"] = bench(train_s, check_s, work)
    run_["runtime_s"] = time.perf_counter() - started
    run_["load_end"] = os.getloadavg()[0]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(document(run_))
    args.out.with_suffix(".json").write_text(json.dumps(run_, indent=1, default=float))
    p = run_["result"]["paths"]
    for key in LABELS:
        print(f"{key}: true states joint 1 {_pct(p[key]['true_states']['joint1'])}, "
              f"validate --model eq. 1 {_pct(p[key]['validate_model']['pipeline'])}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
