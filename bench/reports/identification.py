"""identify --model against the field's standard methods, on a lightly damped cubic
oscillator measured near its bandwidth (bench/cases/oscillator.py), in one run. Prints
markdown tables (not a test).

    .venv/bin/python -m bench.reports.identification [--samples 65000] [--seeds 20]

1. One long log (65,000 samples at 610 Hz, seed 1): identify --model (defaults) on the
   first 80 %; least squares on the same samples with the accelerations from central
   differences of the raw positions, from FFT differentiation, and from the exact
   (noise-free) derivatives of the simulation. Every parameter set is scored on the held-out
   last 20 % by this module's own integrator (Runge-Kutta at 8 sub-steps per sample on
   the exact multisine, from the true state at the held-out start): the RMS of the
   simulated minus the noise-free position, and minus the measured one, relative to the
   position's RMS.
2. Coverage of the standard errors: identify on --seeds logs of 4,000 samples (other
   multisine phases and noise); the share of parameters within 1 and 2 of their standard
   errors of the truth (about 68 % and 95 % when they mean what they say).
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.cases import oscillator
from harness.cli import main

TRUTH = np.array([oscillator.TRUTH[n] for n in oscillator.NAMES])
ESTIMATION_SHARE = 0.8
EDGE = 200  # samples dropped at each end of a derivative-based regression


def regressor(y: np.ndarray, yd: np.ndarray, ydd: np.ndarray) -> np.ndarray:
    """Columns of m, d, k, k3."""
    return np.column_stack([ydd, yd, y, y ** 3])


def least_squares(y, yd, ydd, u) -> np.ndarray:
    keep = slice(EDGE, len(y) - EDGE)
    return np.linalg.lstsq(regressor(y, yd, ydd)[keep], u[keep], rcond=None)[0]


def fft_derivatives(y: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """First and second derivatives by the discrete Fourier transform of the record."""
    omega = 2j * np.pi * np.fft.rfftfreq(len(y), step)
    spectrum = np.fft.rfft(y)
    return (np.fft.irfft(omega * spectrum, len(y)), np.fft.irfft(omega ** 2 * spectrum, len(y)))


def held_out_errors(theta: np.ndarray, log: oscillator.Log, start: int
                    ) -> tuple[float, float]:
    """Relative RMS of the free run from the true state at ``start`` to the end, against
    the noise-free and against the measured position."""
    fine = log.u_fine[2 * oscillator.FINE * start:]
    y, _, _ = oscillator.free_run(theta, fine, log.y_true[start], log.yd_true[start])
    if not np.all(np.isfinite(y)):
        return float("inf"), float("inf")
    scale = np.sqrt(np.mean(log.y_true[start:] ** 2))
    return (float(np.sqrt(np.mean((y - log.y_true[start:]) ** 2)) / scale),
            float(np.sqrt(np.mean((y - log.y[start:]) ** 2)) / scale))


def identify(log: oscillator.Log, samples: int, folder: Path) -> tuple[dict, float]:
    """identify --model on the first ``samples`` samples: its summary and wall time."""
    part = oscillator.Log(log.t[:samples], log.y[:samples], log.u[:samples], log.u_fine,
                          log.y_true[:samples], log.yd_true[:samples], log.ydd_true[:samples])
    oscillator.write(part, folder / "log.csv", folder / "model.toml")
    start = time.perf_counter()
    code = main(["identify", str(folder / "log.csv"), "--model", str(folder / "model.toml"),
                 "--out", str(folder / "id")])
    seconds = time.perf_counter() - start
    if code not in (0, 1):
        raise SystemExit(f"identify failed ({code})")
    return json.loads((folder / "id" / "identification.json").read_text()), seconds


def long_log_table(samples: int) -> str:
    log = oscillator.make_log(1, samples)
    split = int(ESTIMATION_SHARE * samples)
    step = 1.0 / oscillator.RATE
    y, u = log.y[:split], log.u[:split]
    with tempfile.TemporaryDirectory() as folder:
        summary, seconds = identify(log, split, Path(folder))
    ours = np.array([summary["parameters"][n]["value"] for n in oscillator.NAMES])
    ours_std = np.array([summary["parameters"][n]["std_error"] for n in oscillator.NAMES])
    central_d = np.gradient(y, step)
    rows = {
        "identify --model (defaults)": (ours, ours_std),
        "least squares, central differences": (
            least_squares(y, central_d, np.gradient(central_d, step), u), None),
        "least squares, FFT derivatives": (least_squares(y, *fft_derivatives(y, step), u), None),
        "least squares, exact derivatives (noise-free)": (
            least_squares(log.y_true[:split], log.yd_true[:split], log.ydd_true[:split], u),
            None),
    }
    lines = [f"Cubic oscillator, {samples} samples at {oscillator.RATE:g} Hz (resonance 68 Hz), "
             f"0.5 % output noise; estimation on the first {split}, simulation scored on the "
             f"last {samples - split}. identify chose: "
             f"{summary['pipeline_choice']['chosen']['differentiator']} derivatives at "
             f"{summary['pipeline_choice']['chosen']['cutoff_hz']:.4g} Hz, then "
             f"{summary['method']}; {seconds:.1f} s.", "",
             "| method | m | d | k | k3 | held-out simulation error: against the noise-free "
             "output | against the measured output | worst parameter error [standard "
             "errors] |", "|---|---|---|---|---|---|---|---|",
             "| truth | " + " | ".join(f"{v:.6g}" for v in TRUTH) + " | - | - | - |"]
    for name, (theta, std) in rows.items():
        clean, measured = held_out_errors(theta, log, split)
        worst = f"{np.max(np.abs(theta - TRUTH) / std):.2f}" if std is not None else "-"
        lines.append(f"| {name} | " + " | ".join(f"{v:.6g}" for v in theta)
                     + f" | {100 * clean:.3f} % | {100 * measured:.3f} % | {worst} |")
    return "\n".join(lines)


def coverage_table(seeds: int, samples: int = 4000) -> str:
    within = {1: 0, 2: 0}
    total, refined, times = 0, 0, []
    for seed in range(100, 100 + seeds):
        log = oscillator.make_log(seed, samples)
        with tempfile.TemporaryDirectory() as folder:
            summary, seconds = identify(log, samples, Path(folder))
        times.append(seconds)
        refined += summary["method"] == "output error"
        for k, name in enumerate(oscillator.NAMES):
            p = summary["parameters"][name]
            z = abs(p["value"] - TRUTH[k]) / p["std_error"]
            within[1] += z <= 1
            within[2] += z <= 2
            total += 1
    return (f"Coverage over {seeds} logs of {samples} samples ({total} parameter estimates; "
            f"{refined} refined by output error; median {np.median(times):.1f} s per log): "
            f"{100 * within[1] / total:.0f} % within 1 standard error (68 % expected), "
            f"{100 * within[2] / total:.0f} % within 2 (95 % expected).")


def main_bench() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=65_000)
    parser.add_argument("--seeds", type=int, default=20)
    args = parser.parse_args()
    print(long_log_table(args.samples))
    print()
    print(coverage_table(args.seeds))


if __name__ == "__main__":
    main_bench()
