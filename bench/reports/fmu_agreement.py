"""The model file's FMU online against identify offline, and whether the FMU's standard
errors cover the truth, on simulated EMPS-like logs. Prints markdown tables (not a test).

    .venv/bin/python -m bench.reports.fmu_agreement [--seeds 50] [--identify-seeds 10]
        [--seconds 20]

The plant is the EMPS drive's model (examples/emps/emps.toml) at the published IDIM-LS
values, M x'' + Fv x' + Fc sign(x') + OF = gtau vir, in closed loop with a PD
controller at 1 kHz on the measured position (the input held over each sample, as a
drive's), tracking a sum of sines of +-0.1 m; Runge-Kutta at 10 sub-steps per sample.
The position is measured with white noise of 2 um (other seeds: other noise and other
reference phases). Per seed: the FMU fed sample by sample through fmpy (communication
step = h = the sample period), its final estimates and standard errors; identify
(defaults) on the first --identify-seeds of them.

1. Coverage: the share of seeds whose truth lies within 2 of the FMU's standard errors of
   its estimate, per parameter (about 95 % when they mean what they say), and the ratio
   of the mean reported standard error to the spread of the estimates over the seeds.
2. Agreement: per parameter, the FMU's estimate minus identify's over their combined
   standard error (median and largest over the seeds), and the relative difference.
"""
from __future__ import annotations

import argparse
import csv
import json
import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np

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
    """t, the measured position [m] and the input vir [V] of one closed-loop run."""
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


def run_fmu(fmu: Path, t: np.ndarray, x: np.ndarray, vir: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    signals = np.zeros(len(t), dtype=[("time", float), ("x", float), ("vir", float)])
    signals["time"], signals["x"], signals["vir"] = t, x, vir
    step = 1.0 / RATE
    result = fmpy.simulate_fmu(str(fmu), stop_time=float(t[-1]), step_size=step,
                               output_interval=step, input=signals,
                               start_values={"observer.h": step},
                               output=[*NAMES, *(f"{n}_std" for n in NAMES)])
    return (np.array([result[n][-1] for n in NAMES]),
            np.array([result[f"{n}_std"][-1] for n in NAMES]))


def run_identify(folder: Path, t: np.ndarray, x: np.ndarray, vir: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    log = folder / "log.csv"
    with log.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["t", "qm", "vir"])
        writer.writerows(zip(t, x, vir))
    out = folder / "identify"
    main(["identify", str(log), "--model", str(MODEL), "--out", str(out)])
    found = json.loads((out / "identification.json").read_text())["parameters"]
    return (np.array([found[n]["value"] for n in NAMES]),
            np.array([found[n]["std_error"] for n in NAMES]))


def main_report(seeds: int, identify_seeds: int, seconds: float) -> None:
    truth = np.array([TRUTH[n] for n in NAMES])
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        assert main(["fmu", "--model", str(MODEL), "--out", str(root / "fmu")]) == 0
        fmu = root / "fmu" / "emps.fmu"
        online, online_std, offline, offline_std = [], [], [], []
        for seed in range(seeds):
            t, x, vir = simulate(seed, seconds)
            value, std = run_fmu(fmu, t, x, vir)
            online.append(value)
            online_std.append(std)
            if seed < identify_seeds:
                (root / str(seed)).mkdir()
                value, std = run_identify(root / str(seed), t, x, vir)
                offline.append(value)
                offline_std.append(std)
    theta, std = np.array(online), np.array(online_std)
    print(f"## The model FMU on {seeds} simulated EMPS-like logs ({seconds:g} s at "
          f"{RATE:g} Hz, {NOISE * 1e6:g} um noise; {time.perf_counter() - started:.0f} s)\n")
    print("| parameter | truth | FMU mean | within 2 std | mean std / spread |")
    print("|---|---|---|---|---|")
    for k, name in enumerate(NAMES):
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
    print(f"\n## The FMU against identify on the first {count} logs\n")
    print("| parameter | (FMU - identify) / combined std: median, largest | relative: median, "
          "largest | identify within 2 std of the truth |")
    print("|---|---|---|---|")
    for k, name in enumerate(NAMES):
        print(f"| {name} | {np.median(gap[:, k]):+.2f}, {gap[np.argmax(np.abs(gap[:, k])), k]:+.2f} "
              f"| {100 * np.median(relative[:, k]):+.2f} %, "
              f"{100 * relative[np.argmax(np.abs(relative[:, k])), k]:+.2f} % "
              f"| {100 * inside[k]:.0f} % |")


def cli() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=50)
    parser.add_argument("--identify-seeds", type=int, default=10)
    parser.add_argument("--seconds", type=float, default=20.0)
    args = parser.parse_args()
    main_report(args.seeds, args.identify_seeds, args.seconds)


if __name__ == "__main__":
    cli()
