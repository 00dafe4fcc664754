"""Are the reported standard errors right?  Against the spread over noise seeds.

    .venv/bin/python -m bench.reports.standard_errors [--seeds 96] [--plants accurate,rk45-1e-4,euler]
        [--rates 1000] [--noise 1e-5,1e-4,1e-3] [--fmu-dir build/fmus] [--out FILE.md]
        [--set NAME=VALUE ...]

Issue 10: "a standard error for every identified parameter (from the information
matrix and the residual variance) ... consistent with the spread of the estimates
over several noise seeds (within a factor 1.5)".  Data set A of
bench/reports/realdata/plants.py (the pendulum under the open-loop multi-sine torque, 40 s,
Coulomb friction) for each plant kind and rate, the same trajectory measured with
white noise of each std and each seed; the observer FMU's defaults identify gravity,
viscous and Coulomb friction and the input gain from a nominal model that is off (b
10 % high, c = 2.0, 0.1, 0.1), the torque taken as sampled.  Per condition and
parameter:

- SE / spread: the mean reported standard error at the end over the standard
  deviation of the final estimates across the seeds (the target: 1/1.5 to 1.5; the
  spread of S seeds is itself uncertain by about 1/sqrt(2 (S - 1)), 7 % at 96);
- SE / RMS error: against the RMS error from the truth, which adds the bias;
- bias / spread: the mean error over the spread (a bias the standard error cannot
  see, such as the sampled model's mismatch with the plant).

Noise-free rows give the reported standard error and the actual error of the one
noise-free estimate.  Prints a Markdown table (and writes it to --out).
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from bench.reports.realdata import plants
from harness.identify import Recording, identify
from harness.scenarios import J

REPO = Path(__file__).resolve().parents[2]

PARAMETERS = ("gravity", "viscous", "Coulomb", "b")
TRUTH = np.array([*plants.C_TRUE, plants.B_TRUE])
NOMINAL = {"b": 1.1 / J, "c_nominal[1]": 2.0, "c_nominal[2]": 0.1, "c_nominal[3]": 0.1,
           "c_nominal[4]": 0.0, "c_nominal[5]": 0.0, "identifier": 1}


def final_estimates(data: plants.Dataset, y: np.ndarray, fmu: Path,
                    overrides: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """The final estimates (gravity, viscous, Coulomb, b) and their standard errors."""
    out = identify(Recording(data.t, y, data.u), fmu, {**NOMINAL, **overrides},
                   input_hold="sampled")
    estimate = [out[f"theta_hat[1,{k}]"][-1] for k in (1, 2, 3)] + [out["b_hat"][-1]]
    reported = [out[f"theta_std[1,{k}]"][-1] for k in (1, 2, 3)] + [out["b_std"][-1]]
    return np.array(estimate), np.array(reported)


def row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def ratios(values: np.ndarray) -> str:
    return ", ".join(f"{v:.2f}" for v in values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=96)
    parser.add_argument("--plants", default="accurate,rk45-1e-4,euler")
    parser.add_argument("--rates", default="1000")
    parser.add_argument("--noise", default="1e-5,1e-4,1e-3")
    parser.add_argument("--fmu-dir", type=Path, default=REPO / "build" / "fmus")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="an FMU parameter instead of its default (repeatable)")
    args = parser.parse_args()
    overrides = {name: float(value) for name, value in (a.split("=", 1) for a in args.set)}
    fmu = args.fmu_dir / "SuperTwistingObserver.fmu"
    if not fmu.exists():
        parser.error(f"{fmu} does not exist: build the FMUs first (./build.sh fmus)")
    lines = [row(["plant", "rate", "noise [rad]",
                  "SE / spread (" + ", ".join(PARAMETERS) + ")", "SE / RMS error",
                  "bias / spread"]), row(["---"] * 6)]
    print("\n".join(lines), flush=True)
    start = time.perf_counter()
    for rate in (float(r) for r in args.rates.split(",")):
        for kind in args.plants.split(","):
            data = plants.make("A", kind, rate, args.fmu_dir)
            estimate, reported = final_estimates(data, data.x1, fmu, overrides)
            error = np.abs(estimate - TRUTH) / TRUTH
            cells = [kind, f"{rate / 1000:g} kHz", "0",
                     "reported " + ", ".join(f"{v:.1e}" for v in reported / TRUTH)
                     + " (relative)", "actual " + ", ".join(f"{v:.1e}" for v in error), ""]
            lines.append(row(cells))
            print(lines[-1], flush=True)
            for std in (float(s) for s in args.noise.split(",")):
                runs = [final_estimates(data, data.x1 + np.random.default_rng(seed).normal(
                    0.0, std, data.x1.size), fmu, overrides) for seed in range(args.seeds)]
                estimates = np.array([e for e, _ in runs])
                se = np.array([s for _, s in runs]).mean(axis=0)
                spread = estimates.std(axis=0, ddof=1)
                rms = np.sqrt(((estimates - TRUTH) ** 2).mean(axis=0))
                bias = (estimates.mean(axis=0) - TRUTH) / spread
                lines.append(row([kind, f"{rate / 1000:g} kHz", f"{std:g}", ratios(se / spread),
                                  ratios(se / rms), ratios(bias)]))
                print(lines[-1], flush=True)
    print(f"\n{args.seeds} seeds per noise level; {time.perf_counter() - start:.0f} s")
    if args.out:
        args.out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
