"""EMPS end to end: identify --model on the estimation log, validate on the pulses log, the
model file's FMU (fmu --model) fed the estimation log through fmpy, the benchmark's
IDIM-LS computed in the same run, and the causal velocities against a zero-phase
reference. Prints a markdown table (not a test).

    .venv/bin/python -m bench.reports.emps [--data examples/emps/data] [--out DIR]

IDIM-LS here is the published pipeline: qm through a 4th-order Butterworth at 100 Hz,
forward and backward; central differences for the velocity and acceleration; the first
49 samples dropped; the columns [q'', q', sign q', 1] and the force decimated by 10
(8th-order Chebyshev, zero phase); least squares. Its cross-test takes the pulses log
through the same pipeline. The simulation test runs each parameter set's forward model in
the drive's known closed loop on the pulses log (bench/reports/emps_closed_loop.py) and
compares the simulated force with the measured one. The velocity reference is the same zero-phase central
difference; the causal velocities are compared with it after the first 0.5 s
(convergence) and before the last 0.1 s (the filter's end).
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.io
import scipy.signal

from bench.reports.emps_closed_loop import ClosedLoopLog, simulation_errors
from harness.cli import main

REPO = Path(__file__).resolve().parents[2]

PUBLISHED = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "OF": -3.1648}
# estimation, cross-test, closed-loop force error (the benchmark's paper)
PUBLISHED_ERRORS = (0.0408, 0.0598, 0.089)
STEP = 1e-3


SKIP = 49  # the first samples the published pipeline drops


def benchmark_columns(path: Path, cutoff: float = 100.0, filter_force: bool = False
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Columns [q'', q', sign q', 1] and the force at every sample: qm through a 4th-order
    Butterworth of `cutoff` Hz forward and backward (and the force too if filter_force),
    central differences."""
    data = scipy.io.loadmat(path)
    qm, force = data["qm"].ravel(), (data["gtau"] * data["vir"]).ravel()
    b, a = scipy.signal.butter(4, cutoff / (0.5 / STEP))
    q = scipy.signal.filtfilt(b, a, qm)
    qd = np.gradient(q, STEP)
    qdd = np.gradient(qd, STEP)
    if filter_force:
        force = scipy.signal.filtfilt(b, a, force)
    return np.column_stack([qdd, qd, np.sign(qd), np.ones_like(q)]), force


def decimated(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The published pipeline's rows: the first SKIP samples dropped, decimated by 10."""
    return (scipy.signal.decimate(X[SKIP:], 10, axis=0, zero_phase=True),
            scipy.signal.decimate(y[SKIP:], 10, zero_phase=True))


def benchmark_rows(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """The published IDIM-LS pipeline: decimated columns [q'', q', sign q', 1] and force."""
    return decimated(*benchmark_columns(path))


def relative(X: np.ndarray, y: np.ndarray, theta: np.ndarray) -> float:
    return float(np.linalg.norm(y - X @ theta) / np.linalg.norm(y))


def velocity_rms(path: Path, velocity: np.ndarray) -> tuple[float, float]:
    """RMS difference [mm/s] of a causal velocity and of the raw backward difference to
    the zero-phase reference."""
    qm = scipy.io.loadmat(path)["qm"].ravel()
    b, a = scipy.signal.butter(4, 100.0 / (0.5 / STEP))
    reference = np.gradient(scipy.signal.filtfilt(b, a, qm), STEP)
    backward = np.concatenate([[0.0], np.diff(qm) / STEP])
    inside = slice(int(0.5 / STEP), len(qm) - int(0.1 / STEP))

    def rms(v: np.ndarray) -> float:
        return 1e3 * float(np.sqrt(np.mean((v - reference)[inside] ** 2)))
    return rms(velocity), rms(backward)


def observer_velocity(path: Path) -> np.ndarray:
    """The causal velocity identify writes for this log (estimates.csv's der(x))."""
    from harness.model import read_model
    from harness.model.estimates import causal_estimates
    from harness.model.log import read_log
    from harness.model.zero_phase import ZeroPhase, derivatives

    model = read_model(REPO / "examples" / "emps" / "emps.toml")
    log = read_log(path, model)
    return causal_estimates(log, derivatives(log, ZeroPhase.for_log(log)).qdd).velocity[:, 0]


def fmu_run(path: Path, out: Path) -> tuple[np.ndarray, np.ndarray, float]:
    """The model file's FMU (FMI 2) fed the log at its rate through fmpy: its final
    parameters, its velocity der(x) at every sample (at a communication point the FMU has
    the measurements up to the previous one: a prediction one sample ahead), and the wall
    time (export and simulation)."""
    import fmpy

    from harness.model import read_model
    from harness.model.log import read_log

    start = time.perf_counter()
    model_file = REPO / "examples" / "emps" / "emps.toml"
    if main(["fmu", "--model", str(model_file), "--out", str(out / "fmu")]):
        raise SystemExit("fmu failed")
    model = read_model(model_file)
    log = read_log(path, model)
    signals = np.zeros(log.samples, dtype=[("time", float), ("x", float), ("vir", float)])
    signals["time"], signals["x"], signals["vir"] = log.t - log.t[0], log.q[:, 0], log.inputs[:, 0]
    result = fmpy.simulate_fmu(str(out / "fmu" / "emps.fmu"), input=signals, step_size=log.step,
                               output_interval=log.step, stop_time=float(signals["time"][-1]),
                               start_values={"observer.h": log.step},
                               output=[*PUBLISHED, "der(x)"])
    seconds = time.perf_counter() - start
    return (np.array([result[n][-1] for n in PUBLISHED]), np.asarray(result["der(x)"]),
            seconds)


def validate_pipeline(path: Path):
    """The cross-test of validate (its zero-phase pipeline) for any EMPS parameters."""
    from harness.model import read_model
    from harness.model.fit import relative_errors
    from harness.model.log import read_log
    from harness.model.zero_phase import regression

    model = read_model(REPO / "examples" / "emps" / "emps.toml")
    rows = regression(model, read_log(path, model))
    return lambda theta: relative_errors(rows.Y, rows.r, theta)[1]


def run(data: Path, out: Path) -> str:
    estimation, validation = data / "DATA_EMPS.mat", data / "DATA_EMPS_PULSES.mat"
    model = REPO / "examples" / "emps" / "emps.toml"
    start = time.perf_counter()
    if main(["identify", str(estimation), "--model", str(model), "--out", str(out / "id")]):
        raise SystemExit("identify failed")
    seconds = time.perf_counter() - start
    if main(["validate", str(validation), "--model", str(out / "id" / "identified.toml"),
             "--out", str(out / "val")]):
        raise SystemExit("validate failed")
    ours = json.loads((out / "id" / "identification.json").read_text())
    theta = np.array([ours["parameters"][n]["value"] for n in PUBLISHED])
    cross = json.loads((out / "val" / "validation.json").read_text())["relative_error"]["pooled"]

    start = time.perf_counter()
    X, y = benchmark_rows(estimation)
    idim = np.linalg.lstsq(X, y, rcond=None)[0]
    idim_seconds = time.perf_counter() - start
    Xv, yv = benchmark_rows(validation)
    ours_pipeline = validate_pipeline(validation)
    fmu_theta, fmu_velocity, fmu_seconds = fmu_run(estimation, out)
    closed_loop = ClosedLoopLog.read(validation)
    published = np.array(list(PUBLISHED.values()))

    def row(name, values, own, bench_est, bench_cross, secs):
        cells = [f"{v:.4f}" for v in values]
        force, position = simulation_errors(closed_loop, np.asarray(values))
        return (f"| {name} | " + " | ".join(cells) + f" | {100 * bench_est:.3f} % | "
                f"{100 * bench_cross:.3f} % | {100 * own:.3f} % | {100 * force:.3f} % | "
                f"{100 * position:.5f} % | {secs} |")
    lines = ["| method | M [kg] | Fv [N s/m] | Fc [N] | OF [N] | estimation error "
             "(benchmark pipeline) | cross-test (benchmark pipeline) | cross-test "
             "(validate) | closed-loop simulation: force error | position error | time |",
             "|---|---|---|---|---|---|---|---|---|---|---|",
             row("identify --model", theta, cross, relative(X, y, theta),
                 relative(Xv, yv, theta), f"{seconds:.2f} s (command)"),
             row("fmu --model (causal, fmpy)", fmu_theta, ours_pipeline(fmu_theta),
                 relative(X, y, fmu_theta), relative(Xv, yv, fmu_theta),
                 f"{fmu_seconds:.2f} s (export + run)"),
             row("IDIM-LS, this run", idim, ours_pipeline(idim), relative(X, y, idim),
                 relative(Xv, yv, idim), f"{idim_seconds:.2f} s (LS only)"),
             row("IDIM-LS, published values", published, ours_pipeline(published),
                 relative(X, y, published), relative(Xv, yv, published), "-"),
             "", f"The benchmark's paper reports, for its published values, "
             f"{100 * PUBLISHED_ERRORS[0]:.2f} % (estimation), {100 * PUBLISHED_ERRORS[1]:.2f} % "
             f"(cross-test) and a closed-loop force error of about "
             f"{100 * PUBLISHED_ERRORS[2]:.1f} % (its own simulation)."]
    lines += ["", "| log | causal observer velocity (identify) vs zero-phase reference | the "
              "FMU's der(x) (one step ahead) vs the same | raw backward difference vs the same |",
              "|---|---|---|---|"]
    for path in (estimation, validation):
        observer, backward = velocity_rms(path, observer_velocity(path))
        from_fmu = (f"{velocity_rms(path, fmu_velocity)[0]:.3f} mm/s RMS"
                    if path == estimation else "-")
        lines.append(f"| {path.name} | {observer:.3f} mm/s RMS | {from_fmu} | "
                     f"{backward:.3f} mm/s RMS |")
    return "\n".join(lines)


def main_bench() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=REPO / "examples" / "emps" / "data")
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for the commands' outputs (default: a temporary one)")
    args = parser.parse_args()
    if args.out is None:
        with tempfile.TemporaryDirectory() as folder:
            print(run(args.data, Path(folder)))
    else:
        print(run(args.data, args.out))


if __name__ == "__main__":
    main_bench()
