"""Would another zero-phase cut-off identify EMPS better, and could the estimation log
alone tell?  For each cut-off of the inverse-model pipeline (Butterworth on qm and, below
the benchmark's 100 Hz, on the force too; central differences; decimation by 10; least
squares): five-fold cross-validation on the estimation log under the fixed 100 Hz pipeline
(contiguous folds, 0.2 s margins left out of training), and the cross-test and closed-loop
simulation on the validation log (docs/model_files.md, the EMPS walk-through).

    .venv/bin/python -m bench.investigations.emps_cutoffs [--data examples/emps/data]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from bench.reports.emps import SKIP, benchmark_columns, benchmark_rows, decimated
from bench.reports.emps_closed_loop import ClosedLoopLog, simulation_errors

REPO = Path(__file__).resolve().parents[2]
FOLDS, MARGIN = 5, 200
CUTOFFS = (10.0, 20.0, 30.0, 50.0, 100.0)


def columns(path: Path, cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """The benchmark's columns and force at `cutoff`, the force filtered alike below the
    benchmark's 100 Hz."""
    return benchmark_columns(path, cutoff, filter_force=cutoff < 100.0)


def cross_validation(path: Path, cutoff: float) -> float:
    """Pooled relative error on held-out folds, scored by the 100 Hz pipeline."""
    X, y = columns(path, cutoff)
    Xs, ys = columns(path, 100.0)
    n = len(y)
    edges = np.linspace(SKIP, n, FOLDS + 1).astype(int)
    error = 0.0
    for k in range(FOLDS):
        train = np.ones(n, bool)
        train[:SKIP] = False
        train[max(0, edges[k] - MARGIN):edges[k + 1] + MARGIN] = False
        theta = np.linalg.lstsq(X[train][::10], y[train][::10], rcond=None)[0]
        test = slice(edges[k], edges[k + 1])
        error += float(np.sum((ys[test] - Xs[test] @ theta) ** 2))
    return float(np.sqrt(error) / np.linalg.norm(ys[SKIP:]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=REPO / "examples" / "emps" / "data")
    args = parser.parse_args()
    estimation, validation = args.data / "DATA_EMPS.mat", args.data / "DATA_EMPS_PULSES.mat"
    Xv, yv = benchmark_rows(validation)
    loop = ClosedLoopLog.read(validation)
    print("| cut-off | M | Fv | Fc | OF | cross-validation (estimation log) | cross-test | "
          "closed-loop force error |\n|---|---|---|---|---|---|---|---|")
    for cutoff in CUTOFFS:
        theta = np.linalg.lstsq(*decimated(*columns(estimation, cutoff)), rcond=None)[0]
        cross = float(np.linalg.norm(yv - Xv @ theta) / np.linalg.norm(yv))
        print(f"| {cutoff:g} Hz | " + " | ".join(f"{v:.3f}" for v in theta) +
              f" | {100 * cross_validation(estimation, cutoff):.3f} % | {100 * cross:.3f} % | "
              f"{100 * simulation_errors(loop, theta)[0]:.3f} % |")


if __name__ == "__main__":
    main()
