"""Serial robots: identification from joint logs against the field's baselines.

    .venv/bin/python -m bench.reports.robots [--rates 1000,10000] [--seconds 20] [--robots ...]
        [--methods ...] [--model-left-out ROBOT@RATE,...] [--out FILE.md]
        [--results build/robots/results.json]
    .venv/bin/python -m bench.reports.robots --from-results build/robots/results.json --out FILE

--out (default build/reports/robots_results.md) receives the generated results document
(bench/reports/robot_report.py: conditions, the issue's targets judged from the rows, one
table per rate; edit the scripts, not the document).  Every row goes to --results as well, after
each robot and rate, so that the document can be written again without a new run.

Robots: the two-link arm (example-robot-data's double pendulum) with an unknown 0.3 kg
tip payload (unknown: the payload and the friction), the UR5 and the Panda arm with
every base parameter and the friction unknown (the truth: the URDF's links scaled by
0.8..1.2 and friction added).  Each is simulated with Pinocchio (pin.aba, DOP853,
rtol 1e-10) under PD control along a multi-sine; logged noise-free and with 17-bit
encoders.  Truth friction uses a Coulomb term saturated below 0.02 rad/s (a smooth
model the integrator can follow); the identification assumes sign(q').

Methods: the pipeline (harness.robot.pipeline) with Savitzky-Golay velocities ("sg")
and with the causal super-twisting observer ("observer"); the baseline "SG+LS": plain
Savitzky-Golay + torque-space least squares (no reversal mask, no consistency).
The model-based observer of the RobotObserver FMU (bench/reports/robot_observer_methods.py): with
the URDF's model, with the model identified by "sg", and the FMU itself (--methods).
Velocity baseline: a causal steady-state Kalman filter per joint, tuned on the truth
(an oracle tuning: the best a Kalman filter can do).
Metrics: velocity RMS (max over joints), torque prediction error on a separate
validation trajectory (RMS error / RMS torque, true states, the truth's Coulomb shape), payload mass error,
friction errors (max over joints), identification time."""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import shlex
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from bench.reports import REPORTS, commit, robot_report
from bench.reports.realdata.baselines import kalman, tune_log10
from bench.reports.robot_observer_methods import MODEL_METHODS, model_observer
from bench.reports.robot_trajectories import quantize, simulate
from harness.model.fit import fit as least_squares
from harness.robot.base_parameters import base_parameters
from harness.robot.examples import example_urdf
from harness.robot.joint_log import JointLog
from harness.robot.layout import ParameterLayout
from harness.robot.pipeline import identify_robot
from harness.robot.smoothing import savitzky_golay
from harness.robot.urdf import read_urdf

REPO = Path(__file__).resolve().parents[2]

COULOMB_VELOCITY = 0.02
PAYLOAD, TIP = 0.3, np.array([0.0, 0.0, 0.2])


def truth_of(name: str, robot, rng):
    """(link parameters, friction, unknown) of the simulated robot."""
    link = robot.arrays()["link"].copy()
    n = robot.n
    if name == "double_pendulum":
        skew = pin.skew(TIP)
        I = -PAYLOAD * skew @ skew
        link[-1] += [PAYLOAD, *(PAYLOAD * TIP), I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2],
                     I[2, 2]]
        unknown = "payload"
    else:
        link *= rng.uniform(0.8, 1.2, (n, 1))  # a scaled body stays physically consistent
        unknown = "all"
    scale = 0.1 if name == "double_pendulum" else 1.0  # friction in proportion to the torques
    friction = scale * np.column_stack([rng.uniform(0.2, 1.0, n), rng.uniform(0.5, 2.0, n)])
    return link, friction, unknown


def pinocchio_truth(path, locked, link, friction, armature=None):
    """forward(q, qd, tau) of the robot with these link parameters and friction, and with
    `armature` (n,) drive inertias, Ia_i q_i'' added to joint i's torque, if given."""
    model = pin.buildModelFromUrdf(str(path))
    if locked:
        model = pin.buildReducedModel(model, [model.getJointId(j) for j in locked],
                                      pin.neutral(model))
    for i in range(1, model.njoints):
        model.inertias[i] = pin.Inertia.FromDynamicParameters(link[i - 1])
    if armature is not None:  # aba and crba add it to the inertia matrix's diagonal
        model.armature = np.asarray(armature, dtype=float)
    data = model.createData()

    def forward(q, qd, tau):
        fr = friction[:, 0] * qd + friction[:, 1] * np.clip(qd / COULOMB_VELOCITY, -1, 1)
        return pin.aba(model, data, q, qd, tau - fr)
    return forward


def prediction_error(robot, pi, validation) -> float:
    """With the truth's Coulomb shape: what is scored is the identified parameters."""
    _, q, qd, qdd, tau = validation
    link, friction, _ = ParameterLayout(robot.n).split(pi)
    body = robot.rigid_body(link=link, friction=friction, coulomb_velocity=COULOMB_VELOCITY)
    error = body.inverse_dynamics(q, qd, qdd) - tau
    return float(np.sqrt(np.mean(error ** 2)) / np.sqrt(np.mean(tau ** 2)))


def kalman_velocity_rms(q, qd, h, skip) -> list[float]:
    """The oracle-tuned causal Kalman filter's velocity RMS per joint."""
    out = []
    for i in range(q.shape[1]):
        def cost(lam, i=i):
            return float(np.sqrt(np.mean((kalman(q[:, i], h, lam)[1][skip:] - qd[skip:, i]) ** 2)))
        _, best = tune_log10(cost, -18, 0, coarse=1.0)  # lambda ~ h^5: down to 1e-18 at 10 kHz
        out.append(best)
    return out


METHODS = ("sg", "observer", "SG+LS", *MODEL_METHODS)
FMU = REPO / "build" / "fmus" / "RobotObserver.fmu"


def run_case(name: str, rate: float, seconds: float, seed: int = 1,
             methods: tuple[str, ...] = METHODS, fmu: Path = FMU) -> list[dict]:
    path, locked = example_urdf(name)
    robot = read_urdf(path, locked=locked)
    rng = np.random.default_rng(seed)
    link, friction, unknown = truth_of(name, robot, rng)
    forward = pinocchio_truth(path, locked, link, friction)
    nominal = robot.rigid_body()
    gravity = lambda q: nominal.gravity(q)[0]  # noqa: E731
    h = 1.0 / rate
    gains = {"double_pendulum": (50.0, 5.0), "ur5": (400.0, 40.0), "panda": (200.0, 20.0)}[name]
    started = time.perf_counter()
    train = simulate(forward, gravity, robot.n, seconds, h, seed=seed, kp=gains[0], kd=gains[1])
    validation = simulate(forward, gravity, robot.n, seconds / 2, 1e-3, seed=seed + 100,
                          kp=gains[0], kd=gains[1])
    simulated = time.perf_counter() - started
    t, q, qd, _, tau = train
    layout = ParameterLayout(robot.n)
    truth_pi = layout.join(link, friction)
    rows = []
    skip = int(0.5 / h)
    for bits in (None, 17):
        qm = q if bits is None else quantize(q, bits)
        log = JointLog(t, qm, tau)
        kalman_rms = kalman_velocity_rms(qm, qd, h, skip)
        # the model-based methods' identified model and gains
        shared: dict[str, Any] = {"fmu": fmu}
        for method in methods:
            started = time.perf_counter()
            if method in MODEL_METHODS:
                pi, velocity = model_observer(method, robot, log, qd, unknown, skip, shared)
            elif method == "SG+LS":
                qs, qds, qdds, us = savitzky_golay(log, 0.05)
                body = robot.rigid_body()
                base = base_parameters(body, robot.arrays()["types"], robot.joint_names, unknown)
                used = np.arange(skip, len(t) - skip, max(1, (len(t) - 2 * skip) // 20000))
                Y = body.regressor(qs[used], qds[used], qdds[used])
                known = np.setdiff1d(layout.indices(layout.standard),
                                     np.union1d(base.base, base.dependent))
                z = us[used] - Y[:, :, known] @ robot.parameters()[known]
                # torque-space least squares, the joints weighted by their residual RMS
                beta = least_squares(base.regressor(Y), z,
                                     base.project(robot.parameters())).theta
                # prediction with the base parameters directly (no consistency step)
                pi = robot.parameters().copy()  # project(pi) = beta, the known columns kept
                pi[base.dependent] = 0.0
                pi[base.base] = beta
                velocity = qds
            else:
                result = identify_robot(robot, log, unknown=unknown, method=method)
                pi, velocity = result.pi, result.velocity
                if method == "sg":  # the model the model-based methods observe with
                    shared["identified"] = pi
            cost = time.perf_counter() - started
            viscous, coulomb = (np.abs(pi[part] - truth_pi[part]) / truth_pi[part]
                                for part in (layout.viscous_levels, layout.coulomb_levels))
            payload_error = (abs(pi[layout.mass(robot.n - 1)] - link[-1, 0]) / PAYLOAD
                             if name == "double_pendulum" else float("nan"))
            joints = np.sqrt(np.mean((velocity[skip:-skip] - qd[skip:-skip]) ** 2, axis=0))
            rows.append({
                "robot": name, "rate": rate, "encoder": "exact" if bits is None else f"{bits} bit",
                "method": method,
                "velocity_rms": float(joints.max()), "kalman_rms": max(kalman_rms),
                "velocity_rms_joints": [float(v) for v in joints],
                "kalman_rms_joints": kalman_rms,
                "tuned": list(shared["tuned"]) if method in ("model obs (ident.)", "FMU")
                and "tuned" in shared else None,
                "prediction": prediction_error(robot, pi, validation),
                "payload": payload_error,
                "viscous": float(viscous.max()),
                "coulomb": float(coulomb.max()),
                "seconds": cost, "simulation": simulated})
            print(format_row(rows[-1]), flush=True)
    return rows


HEADER = ("| robot | rate | encoder | method | velocity RMS [rad/s] (Kalman) | torque prediction "
          "error | payload mass error | viscous error (max) | Coulomb error (max) | time [s] |\n"
          "|---|---|---|---|---|---|---|---|---|---|")


def format_row(r: dict) -> str:
    payload = "" if np.isnan(r["payload"]) else f"{100 * r['payload']:.3f} %"
    return (f"| {r['robot']} | {r['rate'] / 1000:g} kHz | {r['encoder']} | {r['method']} | "
            f"{r['velocity_rms']:.3g} ({r['kalman_rms']:.3g}) | {100 * r['prediction']:.3f} % | "
            f"{payload} | {100 * r['viscous']:.2f} % | {100 * r['coulomb']:.2f} % | "
            f"{r['seconds']:.1f} |")


def _json_safe(x):  # noqa: ANN001, ANN202 -- NaN (no payload) as null: strict JSON
    if isinstance(x, float) and not np.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    return x


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rates", default="1000", help="comma-separated sampling rates [Hz]")
    parser.add_argument("--seconds", type=float, default=20.0, help="training log length [s]")
    parser.add_argument("--robots", default="double_pendulum,ur5,panda")
    parser.add_argument("--methods", default=",".join(METHODS),
                        help=f"comma-separated, of {', '.join(METHODS)} (FMU after "
                             f"'model obs (ident.)')")
    parser.add_argument("--model-left-out", default="",
                        help="comma-separated ROBOT@RATE (e.g. ur5@10000) where the model-based "
                             "methods (tuned on the truth: slow at 10 kHz) are not run")
    parser.add_argument("--out", type=Path, default=REPORTS / "robots_results.md",
                        help="the generated results document (Markdown; default %(default)s)")
    parser.add_argument("--results", type=Path, default=REPO / "build" / "robots" / "results.json",
                        help="every row as JSON, rewritten after each robot and rate")
    parser.add_argument("--from-results", type=Path, default=None,
                        help="do not run: write --out from a results JSON of an earlier run")
    args = parser.parse_args(argv)
    if args.from_results:
        run = json.loads(args.from_results.read_text())
        robot_report.write_document(args.out, run)
        print(f"wrote {args.out}")
        return 0
    methods = tuple(args.methods.split(","))
    unknown = set(methods) - set(METHODS)
    if unknown:
        parser.error(f"unknown methods {sorted(unknown)}: choose from {METHODS}")
    left_out = [x for x in args.model_left_out.split(",") if x]
    # the FMU as it was when the run started: a rebuild of build/fmus during it does not
    # mix versions
    args.results.parent.mkdir(parents=True, exist_ok=True)
    fmu = args.results.parent / FMU.name
    if "FMU" in methods:
        if not FMU.exists():
            print(f"{FMU} is missing: run ./build.sh fmus", file=sys.stderr)
            return 2
        shutil.copyfile(FMU, fmu)
    run = {
        "command": shlex.join([".venv/bin/python", "-m", "bench.reports.robots",
                               *(sys.argv[1:] if argv is None else argv)]),
        "commit": commit(), "seconds": args.seconds, "seed": 1,
        "robots": args.robots.split(","), "rates": [float(r) for r in args.rates.split(",")],
        "methods": list(methods), "model_left_out": left_out,
        "fmu_sha256": hashlib.sha256(fmu.read_bytes()).hexdigest() if "FMU" in methods else None,
        "load_start": os.getloadavg()[0], "rows": [], "finished": False}
    print(HEADER)
    started = time.perf_counter()
    for name in run["robots"]:
        for rate in run["rates"]:
            chosen = tuple(m for m in methods
                           if m not in MODEL_METHODS or f"{name}@{rate:g}" not in left_out)
            run["rows"] += run_case(name, rate, args.seconds, methods=chosen, fmu=fmu)
            run["runtime_s"] = round(time.perf_counter() - started, 1)
            run["load_end"] = os.getloadavg()[0]
            args.results.write_text(json.dumps(_json_safe(run), indent=1))
    run["finished"] = True
    args.results.write_text(json.dumps(_json_safe(run), indent=1))
    print(f"total run time {time.perf_counter() - started:.0f} s; rows in {args.results}")
    robot_report.write_document(args.out, json.loads(args.results.read_text()))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
