"""Serial robots at rest after an MFF identification: how far the estimates move.

    .venv/bin/python -m bench.investigations.robot_no_excitation [--robots double_pendulum,ur5,panda]
        [--excite 10] [--quiet 60] [--R 0.1] [--rho 1e-6] [--out FILE.md]
        [--logs DIR [--simulate-only]]

Issue 10's target "60 s without excitation: the estimate moves less than 1 %", for the
robots' regressor identifier (fmu/src/core/regressor_identifier.c, MFF).  Each robot of
bench/reports/robots.py (same truth, seed 1, 1 kHz) follows the bench's exciting multi-sine under
PD control for --excite seconds; then its reference stops ("rest": the arm settles and
stays) or moves on at 0.01 rad/s on every joint ("creep": slower than the identifier's
min_speed 0.05 rad/s), for --quiet seconds.  Logged noise-free and with 17-bit encoders.

The RobotObserver's path (RigidBody.observe, the FMU's C core, which the FMU equals to
the last bit) with the model the sg pipeline identified from the excitation (the
row "model obs (ident.)" of docs/robots.md, its tuned gains), MFF over every base
parameter (or the payload) and the friction, identifier from 0.2 s on, FMU defaults
otherwise (R 0.1, rho 1e-6, tau 10 ms); rule "default": min_speed 0.05 rad/s and
reversal_margin 0.02 s; rule "every": both 0, every joint equation used, so the rest's
samples (gravity, and sign(q') of a velocity estimate that is not exactly 0) reach the
identifier.

Metrics, between the end of the excitation and every checkpoint of the quiet phase
(0.5, 1, 2, 5, 20, 60 s; the largest; in brackets the torque's from 2 s on, the arm at
rest or creeping, without the ring-down):
- torque: RMS of Y (beta(t) - beta(end of excitation)) over the excitation's true states,
  divided by the RMS torque there (how much the identified model's torque prediction
  moves);
- friction: the largest relative change of a viscous or Coulomb estimate;
- base: |beta(t) - beta(end)| / |beta(end)|;
- trace(Gamma) at the end of the quiet phase over that at the end of the excitation
  (the bound: p / rho);
and, at the end of the excitation, the torque prediction error of the estimate (same
states, against the true torques): the tracking that a leave-out rule must not spoil."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from bench.reports.robot_trajectories import multisine, quantize, simulate
from bench.reports.robots import pinocchio_truth, truth_of
from harness.robot.base_parameters import base_parameters
from harness.robot.examples import example_urdf
from harness.robot.joint_log import JointLog
from harness.robot.layout import ParameterLayout
from harness.robot.pipeline import identify_robot
from harness.robot.urdf import read_urdf

RATE = 1000.0
CREEP = 0.01  # rad/s
JOG, JOG_TIME, JOG_START, JOG_PERIOD = 0.02, 0.5, 3.0, 10.0  # rad, s: 0.13 rad/s at most
VARIANTS = {"rest": (0.0, False), "creep": (CREEP, False), "jogs": (0.0, True)}  # creep, jogs
QUIET_RTOL = 1e-8  # the quiet phase's tolerance (the excitation's: 1e-10)
CHECKPOINTS = (0.5, 1.0, 2.0, 5.0, 20.0, 60.0)  # s after the excitation
SETTLED = 2.0  # s: the arm has come to rest (or to its creep) by then
START = 0.2  # s: the identifier starts after the observer's transient
GAINS = {"double_pendulum": (50.0, 5.0), "ur5": (400.0, 40.0), "panda": (200.0, 20.0)}
# the observer's (alpha1, alpha2), tuned on the truth for "model obs (ident.)" at 1 kHz
# (bench/reports/robot_observer_methods.py; docs/robots.md), v_s = 0.02; exact and 17 bit
TUNED = {"double_pendulum": ((10.0, 0.95), (0.75, 0.87)), "ur5": ((5.6, 0.71), (0.56, 0.75)),
         "panda": ((4.2, 20.5), (1.0, 1.0))}
RULES = {"default": {}, "every": {"min_speed": 0.0, "reversal_margin": 0.0}}


def quiet_reference(n: int, seed: int, excite: float, creep: float, jogs: bool = False):
    """The bench's multi-sine until `excite`, then held (creep 0) or ramping at `creep`;
    with jogs, a bump of JOG on every joint for JOG_TIME s every JOG_PERIOD s."""
    moving = multisine(n, seed)
    held, _ = moving(excite)

    def reference(t: float) -> tuple[np.ndarray, np.ndarray]:
        if t < excite:
            return moving(t)
        q, qd = held + creep * (t - excite), np.full(n, creep)
        s = (t - excite - JOG_START) % JOG_PERIOD
        if jogs and t - excite >= JOG_START and s < JOG_TIME:
            w = 2 * np.pi / JOG_TIME
            q, qd = q + JOG * (1 - np.cos(w * s)) / 2, qd + JOG * w * np.sin(w * s) / 2
        return q, qd
    return reference


def make_logs(name: str, excite: float, quiet: float, seed: int = 1,
              cache: Path | None = None) -> dict:
    """The bench's robot and truth; per quiet phase (t, q, qd, qdd, tau) of the whole run
    (kept in, or read from, cache/NAME-EXCITE-QUIET.npz: the runs of two checkouts share
    the simulation)."""
    path, locked = example_urdf(name)
    robot = read_urdf(path, locked=locked)
    rng = np.random.default_rng(seed)
    link, friction, unknown = truth_of(name, robot, rng)
    case = {"name": name, "robot": robot, "unknown": unknown, "runs": {}}
    stored = cache / f"{name}-{excite:g}-{quiet:g}-{seed}.npz" if cache else None
    if stored is not None and stored.exists():
        data = np.load(stored)
        for variant in VARIANTS:
            case["runs"][variant] = [data[f"{variant}-{k}"] for k in range(5)]
        return case
    forward = pinocchio_truth(path, locked, link, friction)
    nominal = robot.rigid_body()
    gravity = lambda q: nominal.gravity(q)[0]  # noqa: E731
    h, (kp, kd) = 1.0 / RATE, GAINS[name]
    first = simulate(forward, gravity, robot.n, excite, h, seed=seed, kp=kp, kd=kd)
    for variant, (creep, jogs) in VARIANTS.items():
        reference = quiet_reference(robot.n, seed, excite, creep, jogs)
        start = (first[0][-1], first[1][-1], first[2][-1])
        # Radau: at rest the saturated Coulomb friction is stiff (DOP853 and LSODA crawl)
        second = simulate(forward, gravity, robot.n, quiet, h, seed=seed, kp=kp, kd=kd,
                          reference=reference, start=start, method="Radau", rtol=QUIET_RTOL)
        case["runs"][variant] = [np.concatenate([a, b[1:]]) for a, b in zip(first, second)]
    if stored is not None:
        stored.parent.mkdir(parents=True, exist_ok=True)
        np.savez(stored, **{f"{variant}-{k}": a for variant, run in case["runs"].items()
                            for k, a in enumerate(run)})
    return case


def standard(base, pi_nominal: np.ndarray, beta: np.ndarray) -> np.ndarray:
    pi = pi_nominal.copy()
    pi[base.dependent] = 0.0
    pi[base.base] = beta
    return pi


def measure(case: dict, variant: str, bits: int | None, rule: str, excite: float,
            R: float, rho: float, checkpoints: tuple[float, ...] = CHECKPOINTS) -> dict:
    """The tracking at the end of the excitation and the largest moves after it."""
    robot, unknown = case["robot"], case["unknown"]
    n, h = robot.n, 1.0 / RATE
    t, q, qd, qdd, tau = case["runs"][variant]
    qm = q if bits is None else quantize(q, bits)
    end = int(round(excite * RATE))
    excited_log = JointLog(t[:end + 1], qm[:end + 1], tau[:end + 1])
    if "identified" not in case.setdefault("models", {}).setdefault(bits, {}):
        case["models"][bits]["identified"] = identify_robot(robot, excited_log, unknown=unknown,
                                                            method="sg").pi
    pi = case["models"][bits]["identified"]
    base = base_parameters(robot.rigid_body(), robot.arrays()["types"], robot.joint_names,
                           unknown)
    layout = ParameterLayout(n)
    link, friction, _ = layout.split(pi)
    body = robot.rigid_body(link=link, friction=friction, coulomb_velocity=0.02)
    alpha1, alpha2 = TUNED[case["name"]][bits is not None]
    scale = np.sqrt(np.mean(tau[:end] ** 2, axis=0))
    identify = {"columns": base.base, "kind": "mff", "R": R, "rho": rho, "torque_scale": scale,
                "start": int(START * RATE), **RULES[rule]}

    traces = []

    def beta_at(k: int) -> np.ndarray:
        result = body.observe(qm[:k + 1], tau[:k + 1], h, 0.0, alpha1=alpha1, alpha2=alpha2,
                              identify=identify)
        traces.append(result["gamma_trace"])
        return base.project(pi) + result["delta"]

    # the prediction's states: the excitation's true ones (every 10th sample, after 0.5 s)
    used = np.arange(int(0.5 * RATE), end, 10)
    Y = base.regressor(robot.rigid_body().regressor(q[used], qd[used], qdd[used]))
    known = np.setdiff1d(layout.indices(layout.standard), np.union1d(base.base, base.dependent))
    tau_known = robot.rigid_body().regressor(q[used], qd[used], qdd[used])[:, :, known] @ \
        robot.parameters()[known]
    rms_tau = float(np.sqrt(np.mean(tau[used] ** 2)))
    at_end = beta_at(end)
    friction_end = standard(base, pi, at_end)[layout.friction]
    tracking = float(np.sqrt(np.mean((Y @ at_end + tau_known - tau[used]) ** 2)) / rms_tau)
    moved = {"torque": 0.0, "friction": 0.0, "base": 0.0, "settled": 0.0}
    settled = None
    for seconds in checkpoints:
        beta = beta_at(end + int(round(seconds * RATE)))
        change = beta - at_end
        moved["torque"] = max(moved["torque"],
                              float(np.sqrt(np.mean((Y @ change) ** 2)) / rms_tau))
        friction = standard(base, pi, beta)[layout.friction]
        moved["friction"] = max(moved["friction"],
                                float(np.max(np.abs(friction - friction_end) / np.abs(friction_end))))
        moved["base"] = max(moved["base"], float(np.linalg.norm(change) / np.linalg.norm(at_end)))
        if seconds == SETTLED:
            settled = beta
        elif settled is not None:  # the rest alone: torque prediction moved since SETTLED
            moved["settled"] = max(moved["settled"], float(
                np.sqrt(np.mean((Y @ (beta - settled)) ** 2)) / rms_tau))
    return {"tracking": tracking, **moved, "trace": traces[-1] / traces[0]}


HEADER = ("| robot | quiet phase | encoder | rule | torque prediction error at the end of the "
          "excitation | torque prediction moved (after 2 s) | friction moved (max) | base moved | "
          "trace(Gamma) at the end / at the end of the excitation |\n"
          "|---|---|---|---|---|---|---|---|---|")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robots", default="double_pendulum,ur5,panda")
    parser.add_argument("--excite", type=float, default=10.0, help="excitation [s]")
    parser.add_argument("--quiet", type=float, default=60.0, help="rest or creep [s]")
    parser.add_argument("--R", type=float, default=0.1)
    parser.add_argument("--rho", type=float, default=1e-6)
    parser.add_argument("--variants", default="rest,creep,jogs")
    parser.add_argument("--rules", default="default,every")
    parser.add_argument("--out", default=None, help="write the table (Markdown) here")
    parser.add_argument("--logs", type=Path, default=None,
                        help="keep the simulated runs here (and read them if there)")
    parser.add_argument("--simulate-only", action="store_true", help="with --logs")
    args = parser.parse_args()
    checkpoints = tuple(c for c in CHECKPOINTS if c <= args.quiet)
    started = time.perf_counter()
    lines = [HEADER]
    print(HEADER, flush=True)
    for name in args.robots.split(","):
        case = make_logs(name, args.excite, args.quiet, cache=args.logs)
        if args.simulate_only:
            continue
        for variant in args.variants.split(","):
            for bits in (None, 17):
                for rule in args.rules.split(","):
                    r = measure(case, variant, bits, rule, args.excite, args.R, args.rho,
                                checkpoints)
                    line = (f"| {name} | {variant} | {'exact' if bits is None else '17 bit'} | "
                            f"{rule} | {100 * r['tracking']:.3f} % | {100 * r['torque']:.3f} % "
                            f"({100 * r['settled']:.3f} %) | "
                            f"{100 * r['friction']:.2f} % | {100 * r['base']:.3f} % | "
                            f"{r['trace']:.3g} |")
                    lines.append(line)
                    print(line, flush=True)
    print(f"total run time {time.perf_counter() - started:.0f} s")
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
