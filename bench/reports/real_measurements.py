"""The observer FMU against classical estimators on plant data it did not make itself.

    .venv/bin/python -m bench.reports.real_measurements [--quick | --held-out] [--out DIR]
                                                [--fmu-dir build/fmus] [--jobs N]

Makes the pendulum data (open loop A by four integrators; the paper's closed
loops 6.1/6.2/6.3 and their Euler replays), corrupts the measured angle (noise,
encoders), runs every method on the same samples (the FMU with its defaults and
with the paper's method; a Kalman filter, an RTS smoother and Savitzky-Golay,
each with least squares) and scores them side by side.

Writes OUT/results.json (every raw score), OUT/real_measurements.md and .png (OUT:
--out, default build/real_measurements); without --out the full grid also writes
build/reports/real_measurements.md and .png, the report docs/benchmarks.md points to
(generated: edit this script, not the document).  The grid varies one factor at
a time around the base case (A, accurate, 1 kHz, noise-free, exact b) plus the
crosses listed in GRID_NOTES.  Runs take their FMUs from a copy made at the start,
so a rebuild of build/fmus during a run does not mix versions.

--held-out runs the held-out joints instead (bench/reports/realdata/held_out.py: three
joints of other scales and excitations, 1-10 kHz, sensors partly outside the
tuning grid) into build/held_out (or --out), and without --out also
build/reports/held_out.md and .png: the defaults on data they were not tuned on.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import shutil
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np

from bench.reports import REPORTS
from bench.reports.realdata import held_out, methods, plants, report, scoring, sensors
from harness.scenarios import SCENARIOS

REPO = Path(__file__).resolve().parents[2]

SCENARIO_NAMES = ("6.1-sine", "6.2", "6.3")
RATES = (1000, 10000)
DATASET_ORDER = ("A",) + SCENARIO_NAMES + tuple(held_out.PLANTS)
GRID_NOTES = [
    "every measurement x {accurate, euler} x {1 kHz, 10 kHz} (A, exact b)",
    "every plant kind x {noise-free, 16-bit encoder} x {1 kHz, 10 kHz} (A, exact b)",
    "every model error x {noise-free, 16-bit encoder} (A, accurate, 1 kHz)",
    "every measurement x {accurate, euler} for the closed loops 6.1-sine, 6.2, 6.3 "
    "(10 kHz, the scenario's own nominal model)",
]

Condition = tuple[str, str, int, str, str]  # dataset, plant kind, rate, measurement, model


def full_grid() -> list[Condition]:
    """One factor at a time around the base case, plus the crosses of GRID_NOTES."""
    rows: set[Condition] = set()
    for meas in sensors.MEASUREMENTS:
        for kind in ("accurate", "euler"):
            for rate in RATES:
                rows.add(("A", kind, rate, meas, "b-exact"))
    for kind in plants.PLANT_KINDS:
        for meas in ("clean", "enc-16"):
            for rate in RATES:
                rows.add(("A", kind, rate, meas, "b-exact"))
    for error in sensors.MODEL_ERRORS:
        for meas in ("clean", "enc-16"):
            rows.add(("A", "accurate", 1000, meas, error))
    for name in SCENARIO_NAMES:
        for kind in ("accurate", "euler"):
            for meas in sensors.MEASUREMENTS:
                rows.add((name, kind, 10000, meas, "scenario"))
    return sort(rows)


def quick_grid() -> list[Condition]:
    """A few rows of every kind of condition (under 2 minutes on 2 cores)."""
    rows = [("A", "accurate", 1000, m, "b-exact") for m in ("clean", "noise-1e-4", "enc-16")]
    rows += [("A", "euler", 1000, "clean", "b-exact"), ("A", "rk45-1e-4", 1000, "clean", "b-exact"),
             ("A", "accurate", 1000, "clean", "J+10%")]
    rows += [("A", "accurate", 10000, "clean", "b-exact")]
    rows += [(name, "accurate", 10000, "clean", "scenario") for name in SCENARIO_NAMES]
    rows += [("6.2", "accurate", 10000, "noise-1e-4", "scenario"),
             ("6.2", "euler", 10000, "clean", "scenario")]
    return sort(rows)


def held_out_grid() -> list[Condition]:
    """Every held-out joint x rate x sensor, with the held-out nominal model."""
    return sort([(name, "accurate", rate, meas, sensors.HELD_OUT_MODEL.name)
                 for name in held_out.PLANTS for rate in held_out.RATES
                 for meas in held_out.MEASUREMENTS])


def sort(rows) -> list[Condition]:  # noqa: ANN001
    meas = list(sensors.MEASUREMENTS) + list(sensors.HELD_OUT_MEASUREMENTS)
    models = list(sensors.MODEL_ERRORS) + [sensors.HELD_OUT_MODEL.name, "scenario"]
    return sorted(rows, key=lambda c: (DATASET_ORDER.index(c[0]), plants.PLANT_KINDS.index(c[1]),
                                       c[2], models.index(c[4]), meas.index(c[3])))


# ---- data ----------------------------------------------------------------------------
def data_path(data_dir: Path, name: str, kind: str, rate: int) -> Path:
    """Where a trajectory is saved for the workers."""
    return data_dir / f"{name}_{kind}_{rate}.npz"


def make_data(name: str, kind: str, rates: tuple[int, ...], fmu_dir: Path, data_dir: Path
              ) -> dict[str, object]:
    """One trajectory (per rate for Euler), saved for the row workers."""
    start = time.perf_counter()
    meta: dict[str, object] = {}
    if name in held_out.PLANTS or (name == "A" and kind != "euler"):
        base = held_out.make(name) if name in held_out.PLANTS else \
            plants.make("A", kind, 10000, fmu_dir)
        meta = dict(base.meta)
        for rate in rates:
            base.decimate(10000 // rate).save(data_path(data_dir, name, kind, rate))
    else:
        for rate in rates:
            d = plants.make(name, kind, rate, fmu_dir)
            meta.update(d.meta)
            d.save(data_path(data_dir, name, kind, rate))
            after = d.t >= 1.0
            if kind == "euler":  # Euler's x2_k is the velocity of [t_k, t_k+1]: h a / 2 ahead
                meta[f"half_step_rms_{rate}"] = float(np.sqrt(np.mean((0.5 * d.step * d.acc[after])
                                                                      ** 2)))
            if name != "A":  # the sample-rate ripple the switching controller puts on x2
                ripple = d.x2 - np.convolve(d.x2, np.ones(20) / 20, mode="same")
                meta["ripple_rms"] = float(np.sqrt(np.mean(ripple[after][20:-20] ** 2)))
                meta["bu_std"] = float(np.std(d.b * d.u[after]))
    return {"dataset": name, "plant": kind, "seconds": time.perf_counter() - start, **meta}


# ---- one row -------------------------------------------------------------------------
def run_row(cond: Condition, data_dir: Path, fmu: Path) -> dict[str, Any]:
    """Measure, run every method and score it: one row of results.json."""
    name, kind, rate, meas_name, model = cond
    start = time.perf_counter()
    data = plants.Dataset.load(data_path(data_dir, name, kind, rate))
    meas = sensors.measurement(meas_name)
    # The seed depends on data set and measurement, not on plant kind or rate, so the
    # kinds are compared on the same noise sequence where the lengths agree.
    y = sensors.measure(data.x1, meas, sensors.seed_of(name, meas_name))
    if name not in SCENARIOS:  # open loop: A or a held-out joint
        b_nom, c_nom = sensors.nominal(sensors.model_error(model), data.b, data.c)
        transient = 1.0
    else:
        s = SCENARIOS[name]
        c1, c2, c3 = s.c_nominal[:3]
        b_nom, c_nom = float(s.observer["b"]), (c1, c2, c3)
        transient = s.transient
    case = methods.Case(data, y, meas, b_nom, c_nom, transient)
    estimates = methods.run_all(case, fmu)
    out: dict[str, Any] = {
        "dataset": name, "plant": kind, "rate": rate, "measurement": meas_name, "model": model,
        "kind": case.scenario_kind, "transient": transient, "b_nominal": b_nom,
        "c_nominal": list(c_nom), "methods": {}}
    for m, est in estimates.items():
        out["methods"][m] = {
            "scores": scoring.score(case, est), "tuning": est.tuning, "error": est.error,
            "seconds": round(est.seconds, 3)}
    out["seconds"] = round(time.perf_counter() - start, 3)
    return out


def _json_safe(x):  # noqa: ANN001, ANN202 -- inf/nan as strings: strict JSON
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_json_safe(v) for v in x]
    return x


def notes(data_meta: list[dict], rows: list[dict]) -> list[str]:
    """What the data make true for every method (computed from the data of this run)."""
    def get(name: str, kind: str, key: str) -> float:
        vals = [m[key] for m in data_meta if m["dataset"] == name and m["plant"] == kind
                and key in m]
        return float(vals[0]) if vals else float("nan")

    a1, a10 = get("A", "euler", "half_step_rms_1000"), get("A", "euler", "half_step_rms_10000")
    b_ripple, b_bu = get("6.2", "accurate", "ripple_rms"), get("6.2", "accurate", "bu_std")
    diverged = [r for r in rows if "diverged" in (r["methods"]["fmu-paper"]["error"] or "")]
    rates = sorted({r["rate"] for r in diverged})
    out = [
        "## Reading notes",
        "",
        "* Euler data: x2_k is the velocity of the interval [t_k, t_k+1], half a step ahead "
        "of what the positions around t_k show, so every method meets the floor RMS(h a/2) "
        f"(A: {report.fmt(a1)} rad/s at 1 kHz, {report.fmt(a10)} at 10 kHz).",
        "* Closed loops: the twisting controller switches u every sample (6.2: std of b u "
        f"{report.fmt(b_bu)} rad/s^2), which puts a sample-rate ripple on the true velocity "
        f"(RMS {report.fmt(b_ripple)} rad/s about its 2 ms mean) that only a method using u "
        "can follow. The model-free baselines cannot: it is their velocity floor, and their "
        "zbar and least squares (raw u in the nominal model and the regressor) inherit it. "
        "This is the price of model-free estimation there, not a tuning failure.",
    ]
    if diverged:
        out.append(f"* fmu-paper diverged in {len(diverged)} rows (sample rates "
                   f"{', '.join(f'{r // 1000} kHz' for r in rates)}): the paper form "
                   "integrates Gamma by explicit Euler, stable only while "
                   "h |Gamma| |phi|^2 < 2 (rho = 1e-3); see Failed runs.")
    return out


def grid_conditions() -> list[str]:
    """The plants, sensors and nominal models of the full (and quick) grid."""
    return [
        "* Plant: the paper's pendulum, J x'' = u - (M g L/2) sin x - Vs x' - Ps sign(x') "
        "+ J v - J d x', M = 1.1, g = 9.815, L = 0.9, J = M L^2, Vs = 0.18, Ps = 0.45; "
        "b = 1/J, c = [MgL/(2J), Vs/J, Ps/J] (harness/scenarios.py).",
        "* Data set A, open loop: u = J sum A_i sin(2 pi f_i t + phi_i), f = "
        f"{plants.MULTISINE_FREQUENCIES} Hz, A = {plants.MULTISINE_AMPLITUDES} rad/s^2, 40 s "
        "from rest at 0 (swings to +-1.1 rad, about 120 velocity reversals). Plant kinds: "
        "`accurate` DOP853 rtol = atol = 1e-12 with events at every velocity reversal "
        "(sticking handled: Filippov), `rk45-1e-4`/`rk45-1e-6` RK45 rtol 1e-4/1e-6 (atol "
        "1e-8/1e-10) read from the dense output without event handling, `euler` explicit "
        "Euler at the sample step with u held. 1 kHz and 10 kHz sample the same trajectory "
        "(Euler is integrated at each rate).",
        "* Data set B, the paper's closed loops (harness scenarios 6.1-sine, 6.2, 6.3, the "
        "twisting controller driving the Pendulum FMU: RK4 at 1e-5 s, sampled at 10 kHz): "
        "`accurate` is that record; `euler` re-integrates the same pendulum (the scenario's "
        "v(t), d(t), parameters, start) by explicit Euler at 1e-4 s with the recorded u held "
        "per sample (an open-loop replay). The variable-step kinds are made for A only; "
        "B exists at 10 kHz only.",
        "* Measurements of the angle: noise-free; white Gaussian noise of std 1e-6 ... 1e-3 "
        "rad (seed fixed per data set and level); encoders y = q round(x/q), "
        "q = 2 pi/2^bits, 12/16/20 bits.",
        "* Nominal model (A): `exact b, paper's c` = b = 1/J, c = (2, 0.1, 0.1) as in the "
        "paper's 6.2; `J +-10 %`: every coefficient divided by the wrong inertia "
        "(b' = b/1.1, c' = c/1.1 and likewise 0.9); `c2, c3 x1.5`: friction 50 % high. "
        "B: the scenario's nominal model.",
        "* Grid: base case A / accurate / 1 kHz / noise-free / exact b, plus: "
        + "; ".join(GRID_NOTES) + ".",
    ]


def held_out_conditions() -> list[str]:
    """The held-out grid's plants, sensors and nominal model."""
    joints = [f"`{p.name}`: {p.description}" for p in held_out.PLANTS.values()]
    return [
        "* Why: every default of the FMU (gains, filters, the velocity bank, "
        "tau_identifier) was chosen on the grid of real_measurements.md, one pendulum. "
        "These joints keep the FMU's model structure, x'' = b u - c1 sin x - c2 x' - "
        "c3 sign x', and change the scales the defaults could have been fitted to "
        "(bench/reports/realdata/held_out.py): " + "; ".join(joints) + ".",
        f"* Plant data: DOP853 rtol = atol = 1e-12 with every reversal and stick located "
        f"(as A's `accurate`), {held_out.DURATION:g} s from rest at 0, simulated at "
        f"{held_out.SIMULATION_RATE // 1000} kHz and sampled at "
        + ", ".join(f"{r // 1000}" for r in held_out.RATES)
        + " kHz (2 and 5 kHz: rates no default was tuned at).",
        "* Measurements: " + ", ".join(sensors.measurement(m).label
                                       for m in held_out.MEASUREMENTS)
        + " (noise before the quantizer: counts that jitter).",
        f"* Nominal model: {sensors.HELD_OUT_MODEL.label} (b' = b/1.1, c1' = c1/1.1, "
        "c2' = c2/2.2, c3' = c3/2.2); the FMU identifies b, c1, c2, c3 (LSM).",
    ]


def header(args: argparse.Namespace, grid: list[Condition], fmu_sha: str) -> list[str]:
    """The document's fixed part: command, conditions, methods, metrics."""
    cmd = ".venv/bin/python -m bench.reports.real_measurements" + (
        " --held-out" if args.held_out else " --quick" if args.quick else "")
    if Path(args.fmu_dir).resolve() != (REPO / "build" / "fmus").resolve():
        cmd += f" --fmu-dir {args.fmu_dir}"
    title = ("# Held-out joints: the observer FMU's defaults on plants they were not tuned on"
             if args.held_out else
             "# Observer FMU vs classical estimators on independently made plant data")
    return [
        title,
        "",
        "<!-- GENERATED by bench/reports/real_measurements.py: do not edit, re-run the script. -->",
        "",
        f"Generated by `{cmd}` ({len(grid)} rows; `--jobs` and `--out` do not change the "
        f"numbers). SuperTwistingObserver.fmu SHA-256 `{fmu_sha[:16]}`: the FMU at "
        "`build/fmus` when the run started. Every number below is deterministic (fixed "
        "seeds, fixed grids).",
        "",
        "## Conditions",
        "",
        *(held_out_conditions() if args.held_out else grid_conditions()),
        "",
        "## Methods (all on the same samples)",
        "",
        "* `fmu-default`: `harness.identify.identify` (h = sample step) with only the problem "
        "statement: the nominal model (b, c_nominal[1..5]), `identifier` (1 LSM for the open "
        "loops and 6.2, 0 for 6.1, 2 MFF for 6.3; in 6.3 the damping alone, identify_b off) and how u "
        "was applied (`input_hold`: `sampled` for the open loops' continuous torque, `zoh` for the "
        "controller's held output); everything else, the sensor included, at the FMU's "
        "defaults.",
        "* `fmu-paper`: the same plus `harness.scenarios.PAPER_METHOD` and the paper's "
        "gains and filter: for the open loops the 6.2 values (alpha1 8, alpha2 24, tau 0.002, t_id 1), "
        "for B the scenario's whole observer set-up (also t_id, rho, R, identify[k]); rho "
        "raised to 10 h where the scenario's 1e-3 would make the paper's explicit Euler on "
        "Gamma diverge (1 kHz).",
        "* `kalman`: causal steady-state Kalman filter of the constant-acceleration "
        "(white-jerk) model, model-free; r = noise variance + q_enc^2/12 (at least "
        f"{sensors.R_MIN:g}); the jerk intensity q chosen per row for the best velocity RMS "
        "against the truth (log grid, bandwidth 2 rad/s to Nyquist; tuned on the first "
        f"{methods.TUNE_SPAN:g} s, then run on the whole record). `rts`: the "
        "steady-state RTS smoother of the same model, q tuned likewise. `savgol`: "
        "Savitzky-Golay (cubic, scipy.signal.savgol_filter semantics, mode interp) "
        "derivatives 1 and 2, the window tuned likewise (5 samples to 0.6 s). These "
        "oracle tunings favour the baselines; the FMU methods are not tuned.",
        f"* Baseline parameters: least squares of the acceleration estimate on "
        f"[u, -sin y, -v, -sign v] (b, c1, c2, c3) over t >= {methods.LS_START} s; "
        f"the time to 1 % uses growing windows every {methods.LS_EVERY} s. Perturbation "
        "estimate zbar = acceleration estimate - nominal model acceleration at "
        "(y, velocity estimate, u). 6.3: d(t) by local least squares of zbar = -d v "
        "(kalman: exponential forgetting, causal; rts/savgol: the same forwards and "
        "backwards, centred), "
        f"memory chosen per row from {methods.DAMPING_MEMORIES} s.",
        "* FMU velocity: x2_hat; FMU parameters: theta_hat[1,k] (k = 1..3), b_hat if the "
        "FMU publishes it; zbar = z_eq_filtered; 6.3: d_hat = theta_hat[1,2].",
        "",
        "## Metrics",
        "",
        "After the transient (1 s; 5 s for 6.3): velocity RMS and max error; for A and 6.2 "
        "each parameter's relative error at the end and the time after which it stays "
        "within 1 %; 6.1: RMS(zbar - xi), xi = true acceleration - nominal model at the "
        "true state, and the delay (harness.metrics.best_shift, up to 0.1 s); 6.3: "
        "RMS(d_hat - d) and the lag (up to 2 s); chattering: total variation of zbar per "
        "second. `-`: not delivered; `fail`: the run failed (see the end).",
    ]


def main(argv: list[str] | None = None) -> int:
    """Make the data, run the rows in a process pool, write JSON, markdown and figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="reduced grid (under 2 minutes)")
    parser.add_argument("--held-out", action="store_true",
                        help="the held-out joints' grid (report: held_out.md and .png)")
    parser.add_argument("--out", type=Path, default=None,
                        help="the run's folder: results, data, FMU copies, the report (default "
                             "build/real_measurements, build/held_out with --held-out; the full "
                             "and held-out grids then also write their report into "
                             "build/reports)")
    parser.add_argument("--fmu-dir", type=Path, default=REPO / "build" / "fmus")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--keep-data", action="store_true",
                        help="keep the trajectories in OUT/data (about 200 MB for the full grid)")
    args = parser.parse_args(argv)
    if args.quick and args.held_out:
        parser.error("--quick and --held-out are two different grids: give one")
    t_start = time.perf_counter()
    grid = held_out_grid() if args.held_out else quick_grid() if args.quick else full_grid()
    stem = "held_out" if args.held_out else "real_measurements"
    out: Path = args.out or REPO / "build" / stem
    data_dir, fmu_copy = out / "data", out / "fmus"
    for d in (data_dir, fmu_copy):
        d.mkdir(parents=True, exist_ok=True)
    for fmu in ("SuperTwistingObserver", "Pendulum", "TwistingController"):
        src = Path(args.fmu_dir) / f"{fmu}.fmu"
        if not src.exists():
            print(f"{src} is missing: run ./build.sh fmus", file=sys.stderr)
            return 2
        shutil.copyfile(src, fmu_copy / src.name)
    observer = fmu_copy / "SuperTwistingObserver.fmu"
    fmu_sha = hashlib.sha256(observer.read_bytes()).hexdigest()

    needed: dict[tuple[str, str], set[int]] = {}
    for name, kind, rate, _, _ in grid:
        needed.setdefault((name, kind), set()).add(rate)
    rows: list[dict] = []
    data_meta: list[dict] = []
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        jobs = [pool.submit(make_data, n, k, tuple(sorted(r)), fmu_copy, data_dir)
                for (n, k), r in needed.items()]
        for job in as_completed(jobs):
            data_meta.append(job.result())
        print(f"data: {len(jobs)} trajectories in {time.perf_counter() - t_start:.1f} s",
              file=sys.stderr)
        # Longest rows first (10 kHz, long closed loops), so the pool ends evenly.
        order = sorted(grid, key=lambda c: -(c[2] * (50 if c[0] != "A" else 40)))
        futures = {pool.submit(run_row, c, data_dir, observer): c for c in order}
        for i, job in enumerate(as_completed(futures), 1):
            row = job.result()
            rows.append(row)
            print(f"[{i}/{len(grid)}] {report.short_label(row)}: {row['seconds']:.1f} s",
                  file=sys.stderr)
    rows.sort(key=lambda r: grid.index((r["dataset"], r["plant"], r["rate"],
                                        r["measurement"], r["model"])))
    elapsed = time.perf_counter() - t_start
    (out / "results.json").write_text(json.dumps(_json_safe({
        "grid": "held-out" if args.held_out else "quick" if args.quick else "full",
        "fmu_sha256": fmu_sha,
        "jobs": args.jobs, "runtime_s": round(elapsed, 1), "data": data_meta, "rows": rows}),
        indent=1))
    head = header(args, grid, fmu_sha)
    if not args.held_out:  # the notes read data set A's and the loops' data
        head += [""] + notes(data_meta, rows)
    figure = ((tuple(held_out.PLANTS), sensors.HELD_OUT_MODEL.name) if args.held_out
              else (("A",), "b-exact"))
    targets = [out] + ([] if args.quick or args.out else [REPORTS])
    for target in targets:
        target.mkdir(parents=True, exist_ok=True)
        report.write_markdown(target / f"{stem}.md", rows, head)
        report.write_figure(target / f"{stem}.png", rows, *figure)
    if not args.keep_data:  # regenerated every run; no need to keep 200 MB around
        shutil.rmtree(data_dir, ignore_errors=True)
    print(f"{len(rows)} rows in {elapsed:.1f} s; wrote "
          + ", ".join(str(t / f"{stem}.md") for t in targets)
          + f" and {out / 'results.json'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
