"""`identify --robot` on logs with the properties of real robot logs, against the URDF and
the practitioner's least squares, in one run.

    .venv/bin/python -m bench.reports.robot_real_logs [--quick] [--out FILE.md]

--out (default build/reports/robot_real_logs.md) receives the generated document: the
command, date, commit and load average, one row per case, the per-joint errors and the
targets judged from the numbers.  Edit this script, not the document.

Cases (the robots of bench/reports/robots.py, their truth from `truth_of`: links scaled
0.8..1.2 and friction added; simulated with Pinocchio under PD control along a multi-sine,
`simulate`; a training log and a validation log of another seed, same properties):
  a  UR5 at ~94 Hz on a jittering clock (steps 8-13 ms), torques logged as motor currents
     (per-joint drive gains, identified with --torque-gains), 17-bit encoders;
  b  the two-link arm at 200 Hz, joint 2 passive (torque 0, moved by joint 1), encoder
     steps of 0.01 rad, clock jitter +-10 %;
  b2 case b's logs with identify --window 0.05 and validate --window 0.05 (the fixed
     window of earlier versions, which differentiates the 0.01 rad steps into noise);
  c  the UR5 at 1 kHz, 17 bit, with asymmetric Coulomb friction and a constant torque
     offset per joint in the truth, identified with --joint-terms none (the truth outside
     the identified model's class);
  c2 case c's logs identified with --joint-terms offset,asymmetric-coulomb (the model
     class then holds the truth; the least-squares baseline gets the same columns);
  d  the UR5 at 1 kHz, 17 bit: the clean reference;
  e  the UR5 (6 joints) at ~100 Hz on a jittering clock (steps 8-12 ms), motor currents
     (--torque-gains), 17 bit, with a drive inertia (armature, Ia_i q_i'' added to joint
     i's torque) and a constant torque offset per joint in the truth, identified with
     --joint-terms none (the core's model alone, identify's default before the joint terms
     were chosen by cross-validation);
  e2 case e's logs identified with identify's defaults (--joint-terms auto);
  f, f2  as e, e2 for the Panda (7 joints, fingers locked);
  e3, f3  case e's and f's logs identified with --com-in-geometry (each centre of mass
     inside the box of its body's collision meshes).
Cases e to f3 are also judged on their own targets: every link mass of identified.urdf
within a factor 1.5 of the truth's, identified.urdf's validation error within 2 %
(relative) of the estimate's and at most the least squares'.  Their truth's armature is
a fraction 0.1..0.5 of the diagonal of the URDF's inertia matrix at q = 0, its offsets
0.3..0.6 of the joint's Coulomb level, either sign; their link masses are the truth's of
every case (the URDF's scaled by 0.8..1.2).  A case with an auto twin simulates its logs
once per run: the twin (e2, f2) reuses them when both are run.
Training logs of 40 s (--quick: 8 s), validation logs half as long.
A jittered log is given to identify as it is (identify resamples it itself); only if that
fails does the bench resample it onto its mean step (cubic spline of q, linear
interpolation of u) and identify that. The validation log and the least-squares
baseline's training log are resampled by the bench the same way.

Scores, on the validation log: the torque prediction error of `validate --robot`
(harness.robot.validate.torque_errors: Savitzky-Golay of q and u over the case's window, the
edges left out; RMS error over RMS torque, pooled and per joint) of the URDF, of the identified.urdf
written by the real CLI (a subprocess), of identify's base-parameter estimate
(parameters.csv) and of the practitioner's baseline: Butterworth (4th order) filtfilt of q
and u, central differences, the same base regressor, np.linalg.lstsq.  The same models
are also scored on the validation run's true states and torques (their own error, apart
from the scorer's derivative noise)."""
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
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicHermiteSpline, CubicSpline
from scipy.signal import butter, filtfilt

from bench.reports import REPORTS, commit
from bench.reports.robot_trajectories import multisine, quantize, simulate
from bench.reports.robots import COULOMB_VELOCITY, pinocchio_truth, truth_of
from harness.robot.base_parameters import base_parameters
from harness.robot.examples import example_urdf
from harness.robot.joint_log import JointLog
from harness.robot.joint_terms import SIDECAR_NAME, JointTerms, Sidecar, parse_terms, read_sidecar
from harness.robot.layout import core_layout
from harness.robot.smoothing import savitzky_golay
from harness.robot.urdf import Robot, read_urdf
from harness.robot.validate import filtered_friction_columns, scoring_window, torque_errors

REPO = Path(__file__).resolve().parents[2]
FINE_STEP = 1e-3       # the simulation's step before sampling a jittered clock [s]
UR5_GAINS = (13.2, 13.2, 13.2, 9.8, 9.8, 9.8)  # drive gains [N.m/A] of case a
TARGET_RELATIVE = 0.05  # identified.urdf within 5 % (relative) of the estimate's error
PANDA_GAINS = (20.0, 20.0, 20.0, 20.0, 8.0, 8.0, 8.0)  # drive gains [N.m/A] of case f
ARM_JITTER = (0.008, 0.012)  # clock steps of cases e and f [s]: ~100 Hz
DRIVE_MASS_FACTOR = 1.5  # cases e to f3: every identified mass within x1.5 of the truth's
DRIVE_RELATIVE = 0.02    # and identified.urdf within 2 % (relative) of the estimate's error


@dataclass
class Case:
    """One row: a robot and its log's properties."""
    key: str
    robot: str
    rate: float                       # nominal sampling rate [Hz]
    describe: str
    jitter: tuple[float, float] | None = None   # step = uniform(low, high) [s]
    bits: int | None = 17             # encoder bits per turn, or
    resolution: float | None = None   # an encoder step [rad]
    gains: tuple[float, ...] | None = None  # the log holds currents: torque = gain x current
    passive: tuple[int, ...] = ()     # joints with torque 0
    outside_class: bool = False       # asymmetric Coulomb friction and a torque offset
    pd: tuple[float, float] = (400.0, 40.0)
    window: float | None = None       # identify's and validate's --window [s] (None: theirs)
    joint_terms: str | None = None    # identify's --joint-terms (None: its default, auto)
    drive: bool = False               # armature (drive inertia) and a torque offset
    logs_from: str | None = None      # reuse this case's logs when it ran before in the run
    com_in_geometry: bool = False     # identify --com-in-geometry
    results: dict = field(default_factory=dict)


CASES = (
    Case("a", "ur5", 1 / 0.0105, "UR5, ~94 Hz, clock steps 8-13 ms, motor currents, 17 bit",
         jitter=(0.008, 0.013), gains=UR5_GAINS),
    Case("b", "double_pendulum", 200.0,
         "two-link arm, 200 Hz +-10 % jitter, joint 2 passive, 0.01 rad encoder",
         jitter=(0.9 / 200, 1.1 / 200), bits=None, resolution=0.01, passive=(1,),
         pd=(50.0, 5.0)),
    Case("b2", "double_pendulum", 200.0,
         "case b's logs, identify and validate with --window 0.05",
         jitter=(0.9 / 200, 1.1 / 200), bits=None, resolution=0.01, passive=(1,),
         pd=(50.0, 5.0), window=0.05),
    Case("c", "ur5", 1000.0, "UR5, 1 kHz, 17 bit, asymmetric Coulomb + torque offset, "
         "identify --joint-terms none", outside_class=True, joint_terms="none"),
    Case("c2", "ur5", 1000.0, "case c's logs, identify --joint-terms offset,asymmetric-coulomb",
         outside_class=True, joint_terms="offset,asymmetric-coulomb"),
    Case("d", "ur5", 1000.0, "UR5, 1 kHz, 17 bit (clean reference)"),
    Case("e", "ur5", 100.0, "UR5, ~100 Hz, clock steps 8-12 ms, motor currents, 17 bit, "
         "armature + torque offset, identify --joint-terms none", jitter=ARM_JITTER,
         gains=UR5_GAINS, drive=True, joint_terms="none"),
    Case("e2", "ur5", 100.0, "case e's logs, identify's defaults (--joint-terms auto)",
         jitter=ARM_JITTER, gains=UR5_GAINS, drive=True, logs_from="e"),
    Case("f", "panda", 100.0, "Panda, ~100 Hz, clock steps 8-12 ms, motor currents, 17 bit, "
         "armature + torque offset, identify --joint-terms none", jitter=ARM_JITTER,
         gains=PANDA_GAINS, drive=True, joint_terms="none"),
    Case("f2", "panda", 100.0, "case f's logs, identify's defaults (--joint-terms auto)",
         jitter=ARM_JITTER, gains=PANDA_GAINS, drive=True, logs_from="f"),
    Case("e3", "ur5", 100.0, "case e's logs, identify --com-in-geometry",
         jitter=ARM_JITTER, gains=UR5_GAINS, drive=True, logs_from="e", com_in_geometry=True),
    Case("f3", "panda", 100.0, "case f's logs, identify --com-in-geometry",
         jitter=ARM_JITTER, gains=PANDA_GAINS, drive=True, logs_from="f",
         com_in_geometry=True),
)


# --- the logs ---------------------------------------------------------------------------

def _truth(case: Case, robot: Robot, path: Path, locked: tuple[str, ...]):
    """forward(q, qd, tau) of the simulated robot and what it adds to the model class."""
    rng = np.random.default_rng(1)
    link, friction, _ = truth_of(case.robot, robot, rng)
    # the drive's inertia: a fraction of the URDF's inertia matrix's diagonal at q = 0
    armature = (np.diag(robot.rigid_body().mass_matrix(np.zeros(robot.n))[0])
                * rng.uniform(0.1, 0.5, robot.n)) if case.drive else np.zeros(robot.n)
    forward = pinocchio_truth(path, locked, link, friction, armature if case.drive else None)
    extra: dict = {"true_masses": link[:, 0].tolist()}
    if case.drive:
        # and a constant offset: tau_i = ... + Ia_i q_i'' + offset_i
        offset = friction[:, 1] * rng.uniform(0.3, 0.6, robot.n) * rng.choice([-1, 1], robot.n)
        extra.update(armature=armature.tolist(), torque_offset=offset.tolist())
        inside = forward

        def forward(q, qd, tau):  # noqa: ANN001, ANN202
            return inside(q, qd, tau - offset)
    if case.outside_class:
        # Coulomb f_c + d for q' > 0, f_c - d for q' < 0, and a constant offset
        asymmetry = friction[:, 1] * rng.uniform(0.2, 0.4, robot.n) * rng.choice([-1, 1], robot.n)
        offset = friction[:, 1] * rng.uniform(0.3, 0.6, robot.n) * rng.choice([-1, 1], robot.n)
        extra.update(coulomb_asymmetry=asymmetry.tolist(), torque_offset=offset.tolist())
        symmetric = forward

        def forward(q, qd, tau):  # noqa: ANN001, ANN202
            s = np.clip(qd / COULOMB_VELOCITY, -1, 1)
            return symmetric(q, qd, tau - asymmetry * np.abs(s) - offset)
    return forward, extra


def joint_log(case: Case, robot: Robot, forward, seconds: float, seed: int
              ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, ...]]:
    """((time stamps, encoder readings, logged torque column: torque or current), the true
    (q, q', q'', torque) at the stamps) of one run."""
    n = robot.n
    nominal = robot.rigid_body()
    active = np.ones(n)
    active[list(case.passive)] = 0.0
    kp, kd = case.pd[0] * active, case.pd[1] * active
    reference = multisine(n, seed)

    def gravity(q: np.ndarray) -> np.ndarray:
        return nominal.gravity(q)[0] * active

    h = FINE_STEP if case.jitter is not None else 1.0 / case.rate
    t, q, qd, qdd, tau = simulate(forward, gravity, n, seconds, h, seed=seed, kp=kp, kd=kd,
                                  reference=reference, rtol=1e-9)
    if case.jitter is not None:
        rng = np.random.default_rng(seed + 1000)
        low, high = case.jitter
        stamps = np.cumsum(rng.uniform(low, high, int(seconds / low) + 2))
        stamps = np.concatenate([[0.0], stamps[stamps <= t[-1]]])
        q_at = CubicHermiteSpline(t, q, qd)(stamps)
        qd_at = CubicHermiteSpline(t, qd, qdd)(stamps)
        q_ref = np.array([reference(s) for s in stamps])
        tau = kp * (q_ref[:, 0] - q_at) + kd * (q_ref[:, 1] - qd_at) + \
            np.array([gravity(x) for x in q_at])
        qdd = np.array([forward(a, b, c) for a, b, c in zip(q_at, qd_at, tau)])
        t, q, qd = stamps, q_at, qd_at
    tau[:, list(case.passive)] = 0.0
    truth = (q, qd, qdd, tau.copy())
    if case.resolution is not None:
        q = np.round(q / case.resolution) * case.resolution
    elif case.bits is not None:
        q = quantize(q, case.bits)
    logged = tau / np.asarray(case.gains) if case.gains else tau
    return (t, q, logged), truth


def write_csv(path: Path, t: np.ndarray, q: np.ndarray, u: np.ndarray) -> Path:
    n = q.shape[1]
    header = ",".join(["t", *(f"q{i + 1}" for i in range(n)), *(f"u{i + 1}" for i in range(n))])
    np.savetxt(path, np.column_stack([t, q, u]), delimiter=",", header=header, comments="",
               fmt="%.12g")
    return path


def resample(t: np.ndarray, q: np.ndarray, u: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Onto the mean step: a cubic spline of q, u interpolated linearly."""
    grid = t[0] + np.arange(len(t)) * (t[-1] - t[0]) / (len(t) - 1)
    grid[-1] = t[-1]
    u_grid = np.column_stack([np.interp(grid, t, u[:, i]) for i in range(u.shape[1])])
    return grid, CubicSpline(t, q)(grid), u_grid


# --- identify, the scores ----------------------------------------------------------------

def run_identify(data: Path, urdf: Path, out: Path, locked: tuple[str, ...],
                 gains: tuple[float, ...] | None, window: float | None = None,
                 joint_terms: str | None = None, com_in_geometry: bool = False) -> dict:
    """The real CLI in a subprocess: exit status, wall time, stdout and stderr."""
    command = [sys.executable, "-m", "harness", "identify", str(data), "--robot", str(urdf),
               "--out", str(out)]
    for joint in locked:
        command += ["--lock", joint]
    if gains:
        command += ["--torque-gains", ",".join(f"{g:g}" for g in gains)]
    if window is not None:
        command += ["--window", f"{window:g}"]
    if joint_terms is not None:
        command += ["--joint-terms", joint_terms]
    if com_in_geometry:
        command.append("--com-in-geometry")
    started = time.perf_counter()
    done = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
    return {"rc": done.returncode, "seconds": time.perf_counter() - started,
            "stdout": done.stdout, "stderr": done.stderr.strip(),
            "command": shlex.join(["python", *command[1:]])}


def _regressor(body, base, q, qd, qdd, terms: JointTerms | None = None,
               steps: dict[int, tuple[int, np.ndarray]] | None = None,
               chunk: int = 4000) -> np.ndarray:
    """The base regressor (N, n, r), with the joint terms' columns, computed in chunks;
    `steps` (filtered_friction_columns at the same samples) in place of the Coulomb
    columns."""
    def full(part: slice) -> np.ndarray:
        Y = body.regressor(q[part], qd[part], qdd[part])
        Y = Y if terms is None else terms.extend(Y, qd[part], qdd[part])
        for column, (joint, values) in (steps or {}).items():
            Y[:, joint, column] = values[part]
        return Y
    return np.concatenate([base.regressor(full(slice(k, k + chunk)))
                           for k in range(0, len(q), chunk)])


def base_scores(robot: Robot, base, log: JointLog, beta: np.ndarray, window: float,
                terms: JointTerms | None = None) -> tuple[list[float | None], float]:
    """validate's error definition (torque_errors, the Coulomb columns filtered as the
    measured torque) for a base-parameter vector."""
    q, qd, qdd, u = savitzky_golay(log, window)
    edge = int(np.ceil(window / log.step - 1e-9))
    inside = slice(edge, len(log.t) - edge)
    steps = {column: (joint, values[inside]) for column, (joint, values)
             in filtered_friction_columns(log, qd, window, terms).items()}
    predicted = _regressor(robot.rigid_body(), base, q[inside], qd[inside], qdd[inside],
                           terms, steps) @ beta
    measured = u[inside]
    error = predicted - measured
    scale = np.sqrt(np.mean(measured ** 2, axis=0))
    per_joint = [float(np.sqrt(np.mean(error[:, i] ** 2)) / scale[i]) if scale[i] > 0 else None
                 for i in range(robot.n)]
    return per_joint, float(np.linalg.norm(error) / np.linalg.norm(measured))


def true_state_error(robot: Robot, truth: tuple[np.ndarray, ...], beta: np.ndarray | None = None,
                     base=None, terms: JointTerms | None = None,
                     sidecar: Sidecar | None = None) -> float:
    """The pooled error on the true states and torques (no encoder, no filter): the model's
    own error; `robot`'s inverse dynamics (with a sidecar's joint terms), or the base
    parameters `beta` (with the joint terms' columns)."""
    q, qd, qdd, tau = truth
    if beta is None:
        predicted = robot.rigid_body().inverse_dynamics(q, qd, qdd)
        if sidecar is not None:
            coulomb = robot.arrays()["friction"][:, core_layout().coulomb]
            predicted += sidecar.torque_change(qd, qdd, coulomb)
    else:
        predicted = _regressor(robot.rigid_body(), base, q, qd, qdd, terms) @ beta
    return float(np.linalg.norm(predicted - tau) / np.linalg.norm(tau))


def urdf_scores(robot: Robot, log: JointLog, window: float, sidecar: Sidecar | None = None
                ) -> tuple[list[float | None], float]:
    """validate --robot's errors (per joint, pooled) of a URDF's model (and its sidecar)."""
    _, _, _, per_joint, pooled = torque_errors(robot, log, window, sidecar)
    return list(per_joint.values()), pooled


def cutoff(rate: float) -> float:
    """The baseline's Butterworth cut-off [Hz]: 10 Hz (about 7 times the multi-sine's highest
    frequency, 1.4 Hz), at most a tenth of the rate."""
    return min(10.0, rate / 10.0)


def least_squares_baseline(robot: Robot, base, log: JointLog,
                           terms: JointTerms | None = None) -> np.ndarray:
    """beta of the practitioner's ordinary least squares: Butterworth filtfilt of q and u,
    central differences, the base regressor, np.linalg.lstsq; 0.5 s left out at each end."""
    rate = 1.0 / log.step
    b, a = butter(4, cutoff(rate) / (rate / 2))
    q = filtfilt(b, a, log.q, axis=0)
    u = filtfilt(b, a, log.u, axis=0)
    qd = np.gradient(q, log.step, axis=0)
    qdd = np.gradient(qd, log.step, axis=0)
    edge = int(round(0.5 * rate))
    used = slice(edge, len(log.t) - edge)
    Y = _regressor(robot.rigid_body(), base, q[used], qd[used], qdd[used], terms)
    beta, *_ = np.linalg.lstsq(Y.reshape(-1, Y.shape[-1]), u[used].reshape(-1), rcond=None)
    return beta


def read_estimate(parameters: Path, base) -> np.ndarray:
    """identify's base-parameter estimate (parameters.csv), checked against `base`'s names."""
    with parameters.open() as handle:
        rows = list(csv.DictReader(handle))
    names = [r["parameter"] for r in rows]
    if names != list(base.names):
        raise RuntimeError(f"{parameters}: base parameters {names[:3]}... differ from the "
                           f"bench's {list(base.names)[:3]}...")
    return np.array([float(r["estimate"]) for r in rows])


def run_case(case: Case, train_seconds: float, work: Path, logs: dict | None = None) -> dict:
    """One row; `logs` (by case key) holds the simulated logs of the cases run before, for a
    case whose logs_from names one of them (and receives this case's)."""
    path, locked = example_urdf(case.robot)
    robot = read_urdf(path, locked=locked)
    logs = {} if logs is None else logs
    if case.logs_from in logs:
        extra, train, check, true_states = logs[case.logs_from]
        simulated = 0.0
    else:
        forward, extra = _truth(case, robot, path, locked)
        started = time.perf_counter()
        train, _ = joint_log(case, robot, forward, train_seconds, seed=1)
        check, true_states = joint_log(case, robot, forward, train_seconds / 2, seed=101)
        simulated = time.perf_counter() - started
    logs[case.key] = (extra, train, check, true_states)
    folder = work / case.key
    folder.mkdir(parents=True, exist_ok=True)
    row: dict = {"case": case.key, "describe": case.describe, "robot": case.robot,
                 "joints": robot.joint_names, "samples": len(train[0]),
                 "training_s": train_seconds, "mean_step_ms": 1e3 * float(np.mean(np.diff(train[0]))),
                 "simulation_s": simulated, "truth_extra": extra}
    ran, out = None, folder / "out"
    if case.jitter is not None:
        raw = run_identify(write_csv(folder / "raw.csv", *train), path, folder / "raw_out",
                           locked, case.gains, case.window, case.joint_terms,
                           case.com_in_geometry)
        row["raw_log"] = {"rc": raw["rc"], "stderr": raw["stderr"]}
        train = resample(*train)  # the scorer's and the baseline's even logs
        check = resample(*check)
        if raw["rc"] in (0, 1):  # identify took the log as it is
            ran, out = raw, folder / "raw_out"
    if ran is None:
        data = write_csv(folder / "train.csv", *train)
        ran = run_identify(data, path, out, locked, case.gains, case.window, case.joint_terms,
                           case.com_in_geometry)
    row.update(identify_rc=ran["rc"], identify_s=ran["seconds"], stderr=ran["stderr"],
               identify_command=ran["command"])
    if ran["rc"] not in (0, 1):
        row["failed"] = True
        return row
    summary = json.loads((out / "summary.json").read_text())
    gains = np.asarray(case.gains) if case.gains else 1.0
    validation = JointLog(check[0], check[1], check[2] * gains)  # torques, as validate reads
    training = JointLog(train[0], train[1], train[2] * gains)
    body = robot.rigid_body()
    base = base_parameters(body, robot.arrays()["types"], robot.joint_names, "all")
    nominal_beta = base.project(robot.parameters())
    window = scoring_window(validation) if case.window is None else case.window
    urdf_joint, urdf_pooled = urdf_scores(robot, validation, window)
    same = base_scores(robot, base, validation, nominal_beta, window)[1]
    if abs(same - urdf_pooled) > 1e-6 * urdf_pooled:  # the two scorers agree on the URDF
        raise RuntimeError(f"base-parameter scorer {same} != validate's {urdf_pooled}")
    identified = read_urdf(out / "identified.urdf", locked=locked)
    # the model class identify was given: the URDF's, or with the joint terms (then the
    # identified model's terms come from its sidecar, as validate reads them)
    asked = case.joint_terms
    if "joint_terms_choice" in summary:  # the class identify chose by cross-validation
        asked = summary["joint_terms_choice"]["chosen"]
        row["joint_terms_chosen"] = asked
    asked = None if asked == "none" else asked
    terms = None if asked is None else parse_terms(asked, None)
    sidecar = None
    if terms is not None:
        base = base_parameters(body, robot.arrays()["types"], robot.joint_names, "all",
                               terms=terms)
        sidecar = read_sidecar(out / SIDECAR_NAME, robot.joint_names)
    estimate = read_estimate(out / "parameters.csv", base)
    ols = least_squares_baseline(robot, base, training, terms)
    scores = {"urdf": (urdf_joint, urdf_pooled),
              "identified": urdf_scores(identified, validation, window, sidecar),
              "estimate": base_scores(robot, base, validation, estimate, window, terms),
              "ols": base_scores(robot, base, validation, ols, window, terms)}
    row["true_states"] = {
        "urdf": true_state_error(robot, true_states),
        "identified": true_state_error(identified, true_states, sidecar=sidecar),
        "estimate": true_state_error(robot, true_states, estimate, base, terms),
        "ols": true_state_error(robot, true_states, ols, base, terms)}
    masses_urdf = robot.arrays()["link"][:, core_layout().mass]
    masses = np.array(list(summary["masses"].values()))
    row.update(
        scores={k: {"per_joint": v[0], "pooled": v[1]} for k, v in scores.items()},
        warnings=summary.get("warnings", []), holds=summary.get("identified_urdf_holds"),
        passive=summary.get("passive_joints", []),
        mass_ratio=(masses / masses_urdf).tolist(),
        true_mass_ratio=(np.asarray(extra["true_masses"]) / masses_urdf).tolist(),
        ols_cutoff_hz=cutoff(1.0 / training.step), scoring_window_s=window,
        regression_window_s=summary.get("regression_window_s"))
    e = {k: v[1] for k, v in scores.items()}
    warned = bool(row["warnings"]) or bool(row["stderr"])
    row["targets"] = {
        "identified <= OLS": e["identified"] <= e["ols"],
        "identified within 5 % of estimate": abs(e["identified"] - e["estimate"])
        <= TARGET_RELATIVE * e["estimate"],
        "masses within x2 of URDF": bool(np.all((masses / masses_urdf <= 2.0)
                                                & (masses / masses_urdf >= 0.5))),
        "not worse than URDF without warning": e["identified"] <= e["urdf"] or warned}
    if case.drive:
        identified_masses = identified.arrays()["link"][:, core_layout().mass]
        over_truth = identified_masses / np.asarray(extra["true_masses"])
        row["identified_mass_over_truth"] = over_truth.tolist()
        row["drive_targets"] = {
            "every identified.urdf mass within x1.5 of the truth's": bool(np.all(
                (over_truth <= DRIVE_MASS_FACTOR) & (over_truth >= 1 / DRIVE_MASS_FACTOR))),
            "identified within 2 % of estimate": abs(e["identified"] - e["estimate"])
            <= DRIVE_RELATIVE * e["estimate"],
            "identified <= OLS": e["identified"] <= e["ols"]}
    return row


# --- the document -------------------------------------------------------------------------

def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.2f} %"


def _yes(ok: bool) -> str:
    return "yes" if ok else "**NO**"


def document(run: dict) -> str:
    lines = [
        "# identify --robot on logs with the properties of real robot logs",
        "",
        "Generated by `bench/reports/robot_real_logs.py` (edit the script, not this file).",
        "",
        f"- command: `{run['command']}`",
        f"- date: {run['date']} (UTC), commit {run['commit']}",
        f"- load average (1 min) at start {run['load_start']:.2f}, at end {run['load_end']:.2f}"
        f" (2 cores, shared)",
        f"- run time {run['runtime_s']:.0f} s; training logs {run['seconds']:g} s, validation "
        f"logs (another seed) half as long",
        "",
        "Torque prediction error on the validation log, `validate --robot`'s definition (RMS of "
        "the error over RMS of the measured torque, pooled over the joints; Savitzky-Golay "
        "window: validate's default for the validation log, unless the row says otherwise; the "
        "window column gives it). URDF: the unidentified URDF; identified: identify's identified.urdf; "
        "estimate: identify's base-parameter least squares (parameters.csv); OLS: Butterworth "
        "filtfilt + central differences + np.linalg.lstsq on the same base regressor and the "
        "same (resampled) training log.",
        "",
        "| case | log | samples | identify exit, time | windows: identify's, validate's | URDF | "
        "identified.urdf | estimate | OLS (cut-off) | identified.urdf holds | masses / URDF "
        "(truth's) | warnings (stderr) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in run["rows"]:
        if r.get("failed"):
            lines.append(f"| {r['case']} | {r['describe']} | {r['samples']} | exit "
                         f"{r['identify_rc']} | failed: {r['stderr'][:200]} | | | | | | | |")
            continue
        s = r["scores"]
        ratio = r["mass_ratio"]
        stderr = r["stderr"].replace("\n", "<br>").replace("|", "\\|") or "none"
        lines.append(
            f"| {r['case']} | {r['describe']} | {r['samples']} | {r['identify_rc']}, "
            f"{r['identify_s']:.1f} s | {r['regression_window_s']:.3g} s, "
            f"{r['scoring_window_s']:.3g} s | {_pct(s['urdf']['pooled'])} | "
            f"{_pct(s['identified']['pooled'])} | {_pct(s['estimate']['pooled'])} | "
            f"{_pct(s['ols']['pooled'])} ({r['ols_cutoff_hz']:.3g} Hz) | {r['holds']} | "
            f"{min(ratio):.2f}..{max(ratio):.2f} ({min(r['true_mass_ratio']):.2f}.."
            f"{max(r['true_mass_ratio']):.2f}) | {stderr} |")
    lines += ["", "The same models on the validation run's true states and torques (no encoder, "
              "no filter, no clock jitter): the models' own error, apart from the scorer's "
              "derivative noise.", "",
              "| case | URDF | identified.urdf | estimate | OLS |", "|---|---|---|---|---|"]
    for r in run["rows"]:
        if not r.get("failed"):
            lines.append(f"| {r['case']} | " + " | ".join(
                _pct(r["true_states"][k]) for k in ("urdf", "identified", "estimate", "ols"))
                + " |")
    lines += ["", "## Targets", "",
              "| case | identified.urdf <= OLS | identified.urdf within 5 % of the estimate | "
              "every mass within x2 of the URDF's | never worse than the URDF without a warning |",
              "|---|---|---|---|---|"]
    for r in run["rows"]:
        if not r.get("failed"):
            t = r["targets"]
            lines.append(f"| {r['case']} | " + " | ".join(_yes(v) for v in t.values()) + " |")
    lines += ["", "## Per joint (validation log)", ""]
    for r in run["rows"]:
        if r.get("failed"):
            continue
        lines += [f"Case {r['case']} ({r['describe']}):", "",
                  "| joint | URDF | identified.urdf | estimate | OLS | mass / URDF's (truth's) |",
                  "|---|---|---|---|---|---|"]
        s = r["scores"]
        for i, joint in enumerate(r["joints"]):
            lines.append(f"| {joint} | " + " | ".join(_pct(s[k]['per_joint'][i]) for k in
                                                      ("urdf", "identified", "estimate", "ols"))
                         + f" | {r['mass_ratio'][i]:.3f} ({r['true_mass_ratio'][i]:.3f}) |")
        lines.append("")
    lines += ["## Jittered logs given as they are", ""]
    for r in run["rows"]:
        if "raw_log" in r:
            taken = r["raw_log"]["rc"] in (0, 1)
            lines.append(f"- case {r['case']}: exit {r['raw_log']['rc']}"
                         + ("; identify took the log as it is" if taken else
                            f": `{r['raw_log']['stderr'][:400]}`; the bench then resampled "
                            f"the log onto its mean step ({r['mean_step_ms']:.3f} ms)"))
    extra = [r for r in run["rows"] if "coulomb_asymmetry" in r["truth_extra"]]
    for r in extra:
        lines.append(f"- case {r['case']}, outside the model class: Coulomb asymmetry (N.m) "
                     + ", ".join(f"{x:+.3f}" for x in r["truth_extra"]["coulomb_asymmetry"])
                     + "; torque offset (N.m) "
                     + ", ".join(f"{x:+.3f}" for x in r["truth_extra"]["torque_offset"]))
    lines.append("")
    lines.append("identify commands (the training log written by the bench): ")
    for r in run["rows"]:
        lines.append(f"- {r['case']}: `{r['identify_command']}`")
    drive = [r for r in run["rows"] if "drive_targets" in r]
    if drive:
        lines += ["", *_drive_section(drive)]
    return "\n".join(lines) + "\n"


def _drive_section(rows: list[dict]) -> list[str]:
    """Cases e to f3: drive inertias and torque offsets in the truth, their targets."""
    lines = ["## Drive inertias and torque offsets (6 and 7 joints, ~100 Hz, currents)", "",
             "The truth holds, beyond the URDF's model class, an armature Ia_i (Ia_i q_i'' "
             "added to joint i's torque) and a constant torque offset per joint; its link "
             "masses are the URDF's scaled by 0.8..1.2. Targets: every link mass of "
             "identified.urdf within a factor 1.5 of the truth's; identified.urdf's "
             "validation error within 2 % (relative) of the estimate's and at most the "
             "least squares' (OLS, with the same joint-term columns as the estimate).", "",
             "| case | joint terms | identify time | identified.urdf | estimate | OLS | "
             "identified / estimate - 1 | masses of identified.urdf / truth's | masses "
             "x1.5 | within 2 % | <= OLS |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        s = r["scores"]
        e = {k: s[k]["pooled"] for k in ("identified", "estimate", "ols")}
        terms = "none" if "joint_terms_chosen" not in r else \
            f"auto: {r['joint_terms_chosen']}"
        t = list(r["drive_targets"].values())
        lines.append(
            f"| {r['case']} | {terms} | {r['identify_s']:.1f} s | {_pct(e['identified'])} | "
            f"{_pct(e['estimate'])} | {_pct(e['ols'])} | "
            f"{100 * (e['identified'] / e['estimate'] - 1):+.2f} % | "
            + ", ".join(f"{x:.2f}" for x in r["identified_mass_over_truth"])
            + " | " + " | ".join(_yes(v) for v in t) + " |")
    lines.append("")
    seen = set()
    for r in rows:
        x = r["truth_extra"]
        key = (r["robot"], tuple(x["armature"]))
        if key in seen:
            continue
        seen.add(key)
        lines.append(f"- {r['robot']} truth (case {r['case']}): armature (kg.m^2) "
                     + ", ".join(f"{a:.4g}" for a in x["armature"]) + "; torque offset (N.m) "
                     + ", ".join(f"{o:+.3f}" for o in x["torque_offset"]))
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="8 s training logs instead of 40 s (about 2 minutes, and as much "
                             "again for cases e to f3)")
    parser.add_argument("--cases", default=",".join(c.key for c in CASES),
                        help="comma-separated cases to run, e.g. a,d (default: all)")
    parser.add_argument("--out", type=Path, default=REPORTS / "robot_real_logs.md",
                        help="the generated document (default %(default)s)")
    parser.add_argument("--keep", type=Path, default=None,
                        help="keep the logs and identify's outputs in this folder")
    args = parser.parse_args(argv)
    wanted = [k.strip() for k in args.cases.split(",") if k.strip()]
    chosen = [c for c in CASES if c.key in wanted]
    unknown = set(wanted) - {c.key for c in CASES}
    if unknown or not chosen:
        parser.error(f"--cases: unknown {sorted(unknown)}; choose from "
                     f"{','.join(c.key for c in CASES)}")
    seconds = 8.0 if args.quick else 40.0
    run: dict = {"command": shlex.join(["python", "-m", "bench.reports.robot_real_logs",
                                        *(sys.argv[1:] if argv is None else argv)]),
                 "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M"),
                 "commit": commit(), "seconds": seconds, "load_start": os.getloadavg()[0],
                 "rows": []}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as temporary:
        work = args.keep or Path(temporary)
        logs: dict = {}
        for case in chosen:
            row = run_case(case, seconds, work, logs)
            run["rows"].append(row)
            s = row.get("scores", {})
            print(f"{case.key}: " + ", ".join(f"{k} {_pct(v['pooled'])}" for k, v in s.items())
                  + f"; identify {row['identify_s']:.1f} s", flush=True)
    run["runtime_s"] = time.perf_counter() - started
    run["load_end"] = os.getloadavg()[0]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(document(run))
    args.out.with_suffix(".json").write_text(json.dumps(run, indent=1, default=float))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
