"""What the model file's FMU settings change on the real EMPS log.

    .venv/bin/python -m bench.investigations.emps_fmu_settings [--data DATA_EMPS.mat]

The FMU of examples/emps/emps.toml (FMI 2), fed DATA_EMPS.mat sample by sample through
fmpy at the log's rate (communication step = internal step = the sample period), once per
setting; prints its final M, Fv, Fc, OF with their standard errors, the identifier's
cut-off, and identify's values from the same run for comparison (a markdown table for
docs/design/model_fmu.md). Prints only.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
from pathlib import Path

import numpy as np

from harness.cli import main

REPO = Path(__file__).resolve().parents[2]
NAMES = ("M", "Fv", "Fc", "OF")
#: label -> the FMU's start values besides its step
SETTINGS: dict[str, dict[str, float | int | bool]] = {
    "defaults (the fixed-lag window, scheme 3, nominal model)": {},
    "scheme 2 (no bank)": {"scheme": 2},
    "no nominal model": {"nominal_model": False},
    "`f_plus_x` 1": {"f_plus_x": 1.0},
    "`f_plus_x` 100": {"f_plus_x": 100.0},
    "`tau_identifier` 100 ms": {"tau_identifier": 0.1},
    "`regression` 0, `tau_identifier` 20 ms (the earlier default)": {"regression": 0},
    "`regression` 0, `tau_identifier` 10 ms": {"regression": 0, "tau_identifier": 0.01},
    "`regression` 0, `tau_identifier` 50 ms": {"regression": 0, "tau_identifier": 0.05},
    "`regression` 0, `tau_identifier` 100 ms": {"regression": 0, "tau_identifier": 0.1},
}


def run_fmu(fmu: Path, signals: np.ndarray, step: float,
            settings: dict[str, float | int | bool]) -> tuple[np.ndarray, np.ndarray, float]:
    """The FMU's final estimates, their standard errors and the identifier's cut-off."""
    import fmpy

    outputs = [*NAMES, *(f"{n}_std" for n in NAMES), "observer.identifier_cutoff"]
    start = {"observer.h": step, **{f"observer.{k}": v for k, v in settings.items()}}
    with contextlib.redirect_stdout(io.StringIO()):
        result = fmpy.simulate_fmu(str(fmu), input=signals, step_size=step,
                                   output_interval=step, stop_time=float(signals["time"][-1]),
                                   start_values=start, output=outputs)
    return (np.array([result[n][-1] for n in NAMES]),
            np.array([result[f"{n}_std"][-1] for n in NAMES]),
            float(result["observer.identifier_cutoff"][-1]))


def identify(data: Path, folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """identify --model's values and standard errors on the same log."""
    with contextlib.redirect_stdout(io.StringIO()):
        if main(["identify", str(data), "--model", str(REPO / "examples" / "emps" / "emps.toml"),
                 "--out", str(folder / "identify")]):
            raise SystemExit("identify failed")
    found = json.loads((folder / "identify" / "identification.json").read_text())["parameters"]
    return (np.array([found[n]["value"] for n in NAMES]),
            np.array([found[n]["std_error"] for n in NAMES]))


def main_bench() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path,
                        default=REPO / "examples" / "emps" / "data" / "DATA_EMPS.mat")
    args = parser.parse_args()
    from harness.model import read_model
    from harness.model.log import read_log

    model = read_model(REPO / "examples" / "emps" / "emps.toml")
    log = read_log(args.data, model)
    signals = np.zeros(log.samples, dtype=[("time", float), ("x", float), ("vir", float)])
    signals["time"], signals["x"] = log.t - log.t[0], log.q[:, 0]
    signals["vir"] = log.inputs[:, 0]
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        with contextlib.redirect_stdout(io.StringIO()):
            if main(["fmu", "--model", str(REPO / "examples" / "emps" / "emps.toml"),
                     "--out", str(folder / "fmu")]):
                raise SystemExit("fmu failed")
        fmu = folder / "fmu" / "emps.fmu"
        rows = {label: run_fmu(fmu, signals, log.step, settings)
                for label, settings in SETTINGS.items()}
        offline, offline_std = identify(args.data, folder)
    print(f"`{args.data.name}` through fmpy at {1 / log.step:g} Hz; identify in the same run: "
          + ", ".join(f"{n} {v:.5g} +- {s:.2g}" for n, v, s in zip(NAMES, offline, offline_std))
          + "\n")
    print("| setting | " + " | ".join(NAMES) + " | identifier cut-off |")
    print("|---" * (len(NAMES) + 2) + "|")
    for label, (value, std, cutoff) in rows.items():
        cells = " | ".join(f"{v:.5g} +- {s:.2g}" for v, s in zip(value, std))
        print(f"| {label} | {cells} | {f'{cutoff:g} Hz' if cutoff > 0 else '-'} |")


if __name__ == "__main__":
    main_bench()
