"""The LSM regression's filter (the FMU parameter tau_identifier) on the real-measurement rows.

    .venv/bin/python -m bench.reports.real_measurements --keep-data      # first: data and baselines
    .venv/bin/python -m bench.investigations.identifier_filter [--taus 0.002,0.03,0.05,0.1,0.2]
        [--rows A,6.2] [--results build/real_measurements] [--fmu-dir build/fmus] [--jobs 2]

    # the held-out joints (bench/reports/realdata/held_out.py):
    .venv/bin/python -m bench.reports.real_measurements --held-out --keep-data --out build/held_out
    .venv/bin/python -m bench.investigations.identifier_filter --rows C-fast,C-heavy,C-chirp \
        --results build/held_out

Runs fmu-default (bench/reports/realdata/methods.py) on the rows of bench/reports/real_measurements.py's
grid whose identifier is LSM (data set A and the 6.2 loop, or the held-out joints),
once per value of tau_identifier, on the trajectories that run kept, and prints per
row the worst relative parameter error at the end next to the best baseline's
(Savitzky-Golay, Kalman or RTS + least squares, from that run's results.json) and the
paper's method's.
A "*" marks a value worse than the best baseline.  Prints only (no docs).
"""
from __future__ import annotations

import argparse
import json
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from bench.reports import real_measurements as rm
from bench.reports.realdata import methods

REPO = Path(__file__).resolve().parents[2]

BASELINES = ("kalman", "rts", "savgol")
_PARAMETERS = methods.fmu_parameters  # the bench's problem statement, before the patch below


def _fmu_only(case: methods.Case, fmu: Path) -> dict[str, methods.Estimate]:
    return {"fmu-default": methods.run_fmu(case, "fmu-default", fmu)}


def _row(condition: rm.Condition, data_dir: Path, fmu: Path, tau: float) -> float:
    """The row's worst relative parameter error with tau_identifier = tau (in a worker)."""
    methods.fmu_parameters = lambda case, method: {
        **_PARAMETERS(case, method), "tau_identifier": tau}
    methods.run_all = _fmu_only
    value = rm.run_row(condition, data_dir, fmu)["methods"]["fmu-default"]["scores"].get(
        "param_worst")
    return math.nan if value is None else float(value)


def _score(row: dict, method: str) -> float:
    value = row["methods"][method]["scores"].get("param_worst")
    return math.nan if value is None else float(value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--taus", default="0.002,0.03,0.05,0.1,0.2")
    parser.add_argument("--rows", default="A,6.2", help="data sets of the grid")
    parser.add_argument("--results", type=Path, default=REPO / "build" / "real_measurements")
    parser.add_argument("--fmu-dir", type=Path, default=REPO / "build" / "fmus")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    results = args.results / "results.json"
    if not results.exists() or not (args.results / "data").is_dir():
        parser.error(f"{results} or its data/ are missing: run bench/reports/real_measurements.py "
                     "--keep-data first")
    reference = {(r["dataset"], r["plant"], r["rate"], r["measurement"], r["model"]): r
                 for r in json.loads(results.read_text())["rows"]}
    names = args.rows.split(",")
    grid = [c for c in rm.full_grid() + rm.held_out_grid() if c[0] in names]
    taus = [float(t) for t in args.taus.split(",")]
    fmu = args.fmu_dir / "SuperTwistingObserver.fmu"
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        worst = {tau: list(pool.map(_row, grid, [args.results / "data"] * len(grid),
                                    [fmu] * len(grid), [tau] * len(grid))) for tau in taus}
    print("| row | best baseline | paper | " + " | ".join(f"tau_identifier {t:g} s" for t in taus)
          + " |")
    print("|---" * (3 + len(taus)) + "|")
    behind = {tau: 0 for tau in taus}
    for i, condition in enumerate(grid):
        row = reference[condition]
        best = min(_score(row, m) for m in BASELINES)
        cells = []
        for tau in taus:
            value = worst[tau][i]
            behind[tau] += value > best
            cells.append(f"{value:.2g}{' *' if value > best else ''}")
        label = "/".join(str(x) for x in condition)
        print(f"| {label} | {best:.2g} | {_score(row, 'fmu-paper'):.2g} | " + " | ".join(cells) + " |")
    print("\nrows worse than the best baseline: "
          + ", ".join(f"{tau:g} s: {behind[tau]}" for tau in taus))


if __name__ == "__main__":
    main()
