"""The model file's FMU online against identify offline, and whether the FMU's standard
errors cover the truth, on simulated logs of three cases. Prints markdown tables (not a
test).

    .venv/bin/python -m bench.reports.fmu_agreement [--cases emps,oscillator,two_link]
        [--seeds 50] [--identify-seeds 10] [--seconds S]

emps: the EMPS drive's model (examples/emps/emps.toml) at the published IDIM-LS values,
M x'' + Fv x' + Fc sign(x') + OF = gtau vir, in closed loop with a PD controller at 1 kHz
on the measured position (the input held over each sample, as a drive's), tracking a sum
of sines of +-0.1 m; Runge-Kutta at 10 sub-steps per sample. The position is measured
with white noise of 2 um (other seeds: other noise and other reference phases); 20 s (or
--seconds).

oscillator: the lightly damped cubic oscillator of bench/cases/oscillator.py (resonance
near fs/9 at 610 Hz, broadband multisine, 0.5 % output noise; other seeds: other phases
and noise), 65,000 samples (or --seconds).

two_link: the two-link arm of bench/cases/two_link.py and its model file (joint 2 passive,
joint 1 under PD control along a multi-sine), at a uniform 200 Hz: one run simulated
(Pinocchio), its positions read by an encoder of 0.01 rad steps whose zero lies at a
random point of the step (other seeds: other zeros, hence other quantization errors of
the same motion); 20 s (or --seconds).

Per seed: the FMU fed sample by sample through fmpy (communication step = h = the sample
period), its final estimates, standard errors, the cut-off its identifier chose and
whether the published model creates energy; identify (defaults) on the first
--identify-seeds of them.

1. Coverage: the share of seeds whose truth lies within 2 of the FMU's standard errors of
   its estimate, per parameter (about 95 % when they mean what they say), and the ratio
   of the mean reported standard error to the spread of the estimates over the seeds.
2. Agreement: per parameter, the FMU's estimate minus identify's over their combined
   standard error (median and largest over the seeds), and the relative difference.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import fmpy
import numpy as np

from bench.cases import oscillator, two_link
from bench.reports.robot_real_logs import joint_log
from bench.reports.robots import pinocchio_truth
from harness.cli import main

REPO = Path(__file__).resolve().parents[2]
MODEL = REPO / "examples" / "emps" / "emps.toml"
NAMES = ("M", "Fv", "Fc", "OF")
TRUTH = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "OF": -3.1648}
GAIN = 35.15065188            # gtau [N/V], the model file's constant
RATE, SUBSTEPS = 1000.0, 10
NOISE = 2e-6                  # [m], position measurement noise std
KP, KD = 2.0e5, 3.0e3         # the PD controller [N/m], [N s/m]
FREQUENCIES = (0.11, 0.23, 0.37, 0.61)  # [Hz], the reference's sines


def simulate(seed: int, seconds: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t, the measured position [m] and the input vir [V] of one closed-loop EMPS run."""
    rng = np.random.default_rng(seed)
    phases = rng.uniform(0.0, 2 * np.pi, len(FREQUENCIES))
    samples = int(seconds * RATE)
    t = np.arange(samples) / RATE
    omega = 2 * np.pi * np.array(FREQUENCIES)
    reference = 0.025 * np.sin(np.outer(t, omega) + phases).sum(axis=1)
    reference_rate = 0.025 * (omega * np.cos(np.outer(t, omega) + phases)).sum(axis=1)
    noise = NOISE * rng.standard_normal(samples)
    M, Fv, Fc, OF = (TRUTH[n] for n in NAMES)
    h = 1.0 / (RATE * SUBSTEPS)

    def acceleration(v: float, force: float) -> float:
        return (force - Fv * v - Fc * ((v > 0.0) - (v < 0.0)) - OF) / M

    x = v = 0.0
    measured, inputs = np.empty(samples), np.empty(samples)
    previous = 0.0
    for k in range(samples):
        measured[k] = x + noise[k]
        rate = (measured[k] - previous) * RATE if k else 0.0
        previous = measured[k]
        force = float(KP * (reference[k] - measured[k]) + KD * (reference_rate[k] - rate))
        inputs[k] = force / GAIN
        for _ in range(SUBSTEPS):  # Runge-Kutta with the input held
            a1 = acceleration(v, force)
            v2 = v + 0.5 * h * a1
            a2 = acceleration(v2, force)
            v3 = v + 0.5 * h * a2
            a3 = acceleration(v3, force)
            v4 = v + h * a3
            x += h / 6 * (v + 2 * v2 + 2 * v3 + v4)
            v += h / 6 * (a1 + 2 * a2 + 2 * a3 + acceleration(v4, force))
    return t, measured, inputs


@dataclass(frozen=True)
class Case:
    """A simulated case: its model file, parameters and truth, and its logs."""

    title: str
    names: tuple[str, ...]
    truth: dict[str, float]
    write_model: Callable[[Path], Path]
    #: seed, seconds -> t, the FMU's inputs by name, the log's columns by header
    log: Callable[[int, float], tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]]
    seconds: float   # the default length of a log


def _emps_log(seed: int, seconds: float
              ) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    t, x, vir = simulate(seed, seconds)
    return t, {"x": x, "vir": vir}, {"t": t, "qm": x, "vir": vir}


def _oscillator_model(folder: Path) -> Path:
    path = folder / "oscillator.toml"
    path.write_text(oscillator.MODEL_TOML, encoding="utf-8")
    return path


def _oscillator_log(seed: int, seconds: float
                    ) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    log = oscillator.make_log(seed, int(seconds * oscillator.RATE))
    return log.t, {"y": log.y, "u": log.u}, {"t": log.t, "y": log.y, "u": log.u}


def _two_link_model(folder: Path) -> Path:
    path = folder / "two_link.toml"
    path.write_text(two_link.model_toml(), encoding="utf-8")
    return path


@lru_cache(maxsize=2)
def _two_link_run(seconds: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t, the true positions and the torques of one uniform 200 Hz run."""
    arm, path = two_link.robot()
    link, friction = two_link.truth()
    forward = pinocchio_truth(path, (), link, friction)
    uniform = dataclasses.replace(two_link.CASE, jitter=None, resolution=None, bits=None)
    (t, q, u), _ = joint_log(uniform, arm, forward, seconds, two_link.TRAIN_SEED)
    return t, q, u


def _two_link_log(seed: int, seconds: float
                  ) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    t, q, u = _two_link_run(seconds)
    step = two_link.CASE.resolution
    assert step is not None  # case b reads an encoder of 0.01 rad steps
    zero = np.random.default_rng(seed).uniform(-0.5 * step, 0.5 * step, q.shape[1])
    q = np.round((q + zero) / step) * step - zero
    signals = {"q1": q[:, 0], "q2": q[:, 1], "u1": u[:, 0], "u2": u[:, 1]}
    return t, signals, {"t": t, **signals}


CASES = {
    "emps": Case(f"simulated EMPS-like logs ({RATE:g} Hz, {NOISE * 1e6:g} um noise, closed "
                 "loop, input held)", NAMES, TRUTH, lambda folder: MODEL, _emps_log, 20.0),
    "oscillator": Case(f"cubic oscillator logs ({oscillator.RATE:g} Hz, resonance near fs/9, "
                       f"{100 * oscillator.NOISE:g} % noise)", oscillator.NAMES,
                       oscillator.TRUTH, _oscillator_model, _oscillator_log,
                       65_000 / oscillator.RATE),
    "two_link": Case("two-link arm logs (200 Hz, 0.01 rad encoder, joint 2 passive)",
                     two_link.NAMES, dict(zip(two_link.NAMES,
                                              two_link.base_values(*two_link.truth()))),
                     _two_link_model, _two_link_log, 20.0),
}


def run_fmu(fmu: Path, case: Case, t: np.ndarray, inputs: dict[str, np.ndarray]
            ) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """The FMU's final estimates, standard errors, identifier cut-off and energy flag."""
    signals = np.zeros(len(t), dtype=[("time", float), *((n, float) for n in inputs)])
    signals["time"] = t
    for name, values in inputs.items():
        signals[name] = values
    step = float(t[1] - t[0])
    flags = ["observer.identifier_cutoff", "observer.negative_damping"]
    result = fmpy.simulate_fmu(str(fmu), stop_time=float(t[-1]), step_size=step,
                               output_interval=step, input=signals,
                               start_values={"observer.h": step},
                               output=[*case.names, *(f"{n}_std" for n in case.names), *flags])
    return (np.array([result[n][-1] for n in case.names]),
            np.array([result[f"{n}_std"][-1] for n in case.names]),
            float(result[flags[0]][-1]), bool(result[flags[1]][-1]))


def run_identify(folder: Path, case: Case, model: Path, columns: dict[str, np.ndarray]
                 ) -> tuple[np.ndarray, np.ndarray]:
    log = folder / "log.csv"
    np.savetxt(log, np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="", fmt="%.12g")
    out = folder / "identify"
    main(["identify", str(log), "--model", str(model), "--out", str(out)])
    found = json.loads((out / "identification.json").read_text())["parameters"]
    return (np.array([found[n]["value"] for n in case.names]),
            np.array([found[n]["std_error"] for n in case.names]))


def report_case(case: Case, seeds: int, identify_seeds: int, seconds: float) -> None:
    names = case.names
    truth = np.array([case.truth[n] for n in names])
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        model = case.write_model(root)
        assert main(["fmu", "--model", str(model), "--out", str(root / "fmu")]) == 0
        fmu = root / "fmu" / f"{model.stem}.fmu"
        online, online_std, offline, offline_std = [], [], [], []
        cutoffs, unstable = [], 0
        for seed in range(seeds):
            t, inputs, columns = case.log(seed, seconds)
            value, std, cutoff, creates_energy = run_fmu(fmu, case, t, inputs)
            online.append(value)
            online_std.append(std)
            cutoffs.append(cutoff)
            unstable += creates_energy
            if seed < identify_seeds:
                (root / str(seed)).mkdir()
                value, std = run_identify(root / str(seed), case, model, columns)
                offline.append(value)
                offline_std.append(std)
    theta, std = np.array(online), np.array(online_std)
    chosen = ", ".join(f"{c:g} Hz x {cutoffs.count(c)}" for c in sorted(set(cutoffs)))
    print(f"## The model FMU on {seeds} {case.title}, {seconds:g} s each "
          f"({time.perf_counter() - started:.0f} s)\n")
    print(f"The identifier's cut-off: {chosen}. Published models that create energy: "
          f"{unstable} of {seeds}.\n")
    print("| parameter | truth | FMU mean | within 2 std | mean std / spread |")
    print("|---|---|---|---|---|")
    for k, name in enumerate(names):
        inside = np.mean(np.abs(theta[:, k] - truth[k]) <= 2 * std[:, k])
        ratio = np.mean(std[:, k]) / np.std(theta[:, k], ddof=1)
        print(f"| {name} | {truth[k]:.5g} | {np.mean(theta[:, k]):.5g} | {100 * inside:.0f} % "
              f"| {ratio:.2f} |")
    if not offline:
        return
    ident, ident_std = np.array(offline), np.array(offline_std)
    count = len(ident)
    gap = (theta[:count] - ident) / np.hypot(std[:count], ident_std)
    relative = (theta[:count] - ident) / np.abs(ident)
    inside = np.mean(np.abs(ident - truth) <= 2 * ident_std, axis=0)
    print(f"\n### The FMU against identify on the first {count} logs\n")
    print("| parameter | (FMU - identify) / combined std: median, largest | relative: median, "
          "largest | identify within 2 std of the truth |")
    print("|---|---|---|---|")
    for k, name in enumerate(names):
        print(f"| {name} | {np.median(gap[:, k]):+.2f}, {gap[np.argmax(np.abs(gap[:, k])), k]:+.2f} "
              f"| {100 * np.median(relative[:, k]):+.2f} %, "
              f"{100 * relative[np.argmax(np.abs(relative[:, k])), k]:+.2f} % "
              f"| {100 * inside[k]:.0f} % |")
    print()


def cli() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default=",".join(CASES),
                        help=f"comma-separated, of {', '.join(CASES)}")
    parser.add_argument("--seeds", type=int, default=50)
    parser.add_argument("--identify-seeds", type=int, default=10)
    parser.add_argument("--seconds", type=float, default=None,
                        help="length of each log (default: 20 s for emps and two_link, the "
                             "oscillator's 65,000 samples)")
    args = parser.parse_args()
    keys = args.cases.split(",")
    unknown = [k for k in keys if k not in CASES]
    if unknown:
        parser.error(f"unknown case(s) {', '.join(unknown)}: choose from {', '.join(CASES)}")
    for key in keys:
        case = CASES[key]
        report_case(case, args.seeds, args.identify_seeds, args.seconds or case.seconds)


if __name__ == "__main__":
    cli()
