"""60 s without excitation after a 6.3-kind identification, on every kind of plant data.

    .venv/bin/python -m bench.reports.no_excitation [--out DIR] [--fmu-dir build/fmus] [--jobs N]
    .venv/bin/python -m bench.reports.no_excitation --variants "constant d" --plants euler \
        --measurements clean --set rho=0.1      # a diagnostic subset: prints, no report

Issue 10's target: "60 s without excitation: the estimate moves less than 1 %, on
every kind of plant data".  The experiment: the 6.3 pendulum (time-varying damping
d(t) = 0.5 + 0.6 sin(t/7), Coulomb friction, no viscous friction) driven by data
set A's multi-sine torque for 50 s (the 6.3 record length) while the damping is
identified by MFF; then the torque stops (u = 0) for 60 s.  The pendulum rings
down and sticks in static friction about 2 s later (|c1 sin x| <= c3) and rests.
The damping's regressor is the velocity, so at rest the data say nothing about d:
any movement of the estimate there is the identifier's own.  During the ring-down
the data still carry information; the true damping is therefore held at d(50 s)
from the moment the torque stops, so that the right answer does not move either
(variant "6.3 d(t)"); variant "constant d" (d = 0.5 throughout, the value of
tests/harness/test_windup.py, whose pendulum has no Coulomb friction) separates what
the drift model's slope does.

Open loop rather than the twisting loop so that every plant kind of
bench/reports/realdata/plants.py can be made (a variable-step solver needs a continuous
input).  Both FMU methods of bench/reports/realdata/methods.py on the same samples: the
defaults (fmu-default) and the paper's method (fmu-paper), with 6.3's problem
statement (fmu_parameters) and the torque taken as sampled (input_hold).

Writes OUT/no_excitation.json (OUT: --out, default build/no_excitation) and, for the full
set, the report no_excitation.md and .png into OUT if --out is given, else into
build/reports (generated: edit this script, not the document).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import shutil
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from bench.reports import REPORTS
from bench.reports.realdata import methods, plants, sensors
from harness.scenarios import A_COULOMB, A_GRAVITY, SCENARIOS

REPO = Path(__file__).resolve().parents[2]

RATE = 10000  # Hz: the paper's h = 1e-4 of 6.3
EXCITED, QUIET = 50.0, 60.0  # s
D_MEAN, D_AMPLITUDE, D_PERIOD = 0.5, 0.6, 7.0  # the Pendulum FMU's d(t) (6.3)
C_63 = (A_GRAVITY, 0.0, A_COULOMB)  # 6.3's plant: no viscous friction
VARIANTS = {"6.3 d(t)": "d(t) = 0.5 + 0.6 sin(t/7), held at d(50 s) once the torque stops",
            "constant d": "d = 0.5 throughout"}
MEASUREMENTS = ("clean", "noise-1e-5", "enc-16", "enc-12")
TARGET = 0.01  # the 1 %
AT_REST_SPEED = 1e-3  # rad/s: the pendulum is "at rest" once |x2| stays below this


def torque(t: np.ndarray | float) -> np.ndarray:
    """Data set A's multi-sine during the excitation, then nothing."""
    t = np.asarray(t, dtype=float)
    return np.where(t < EXCITED, plants.multisine(t), 0.0)


def damping_63(t: np.ndarray | float) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    return D_MEAN + D_AMPLITUDE * np.sin(np.minimum(t, EXCITED) / D_PERIOD)


def damping_constant(t: np.ndarray | float) -> np.ndarray:
    return np.full_like(np.asarray(t, dtype=float), D_MEAN)


DAMPINGS = {"6.3 d(t)": damping_63, "constant d": damping_constant}


def make_data(variant: str, kind: str, data_dir: Path) -> dict[str, Any]:
    """One trajectory (EXCITED + QUIET seconds at RATE), saved for the row workers."""
    start = time.perf_counter()
    damping = DAMPINGS[variant]
    duration = EXCITED + QUIET
    if kind == "accurate":
        data = plants.open_loop_accurate(RATE, duration, breaks=(EXCITED,), torque=torque,
                                         c=C_63, damping=damping)
    elif kind == "euler":
        data = plants.open_loop_euler(RATE, duration, torque=torque, c=C_63, damping=damping)
    else:
        data = plants.open_loop_rk45(kind, RATE, duration, stop_after=EXCITED, torque=torque,
                                     c=C_63, damping=damping)
    data.name = "6.3"  # the problem statement of 6.3 (methods.fmu_parameters)
    data.save(data_path(data_dir, variant, kind))
    rest = at_rest_from(data.t, data.x2)
    i = int(np.searchsorted(data.t, rest))
    return {"variant": variant, "plant": kind, "seconds": round(time.perf_counter() - start, 1),
            "at_rest_from": rest, "rest_angle": float(data.x1[-1]),
            # a plant that does not stick creeps: its mean velocity at rest
            "creep": float((data.x1[-1] - data.x1[i]) / (data.t[-1] - data.t[i]))}


def data_path(data_dir: Path, variant: str, kind: str) -> Path:
    return data_dir / f"{variant.replace(' ', '_').replace('(', '').replace(')', '')}_{kind}.npz"


def at_rest_from(t: np.ndarray, x2: np.ndarray) -> float:
    """The first time after the torque stops from which |x2| stays below AT_REST_SPEED."""
    moving = np.nonzero((np.abs(x2) >= AT_REST_SPEED) & (t >= EXCITED))[0]
    return float(t[min(moving[-1] + 1, len(t) - 1)]) if len(moving) else EXCITED


def quiet_scores(t: np.ndarray, out: dict[str, np.ndarray], d_true: float, rest: float
                 ) -> dict[str, float]:
    """How far d_hat = theta_hat[1,2] moves over the quiet 60 s, relative to its value
    when the torque stops; trace(Gamma) and the trust outputs at the end."""
    d_hat = out["theta_hat[1,2]"]
    i0, i_rest = int(np.searchsorted(t, EXCITED)) - 1, int(np.searchsorted(t, rest))
    start = float(d_hat[i0])
    quiet = d_hat[i0:]
    move = np.abs(quiet - start) / abs(start)
    k = int(np.argmax(move))
    at_rest = float(np.max(np.abs(d_hat[i_rest:] - d_hat[i_rest])) / abs(start))
    late = int(np.searchsorted(t, rest + 1.0))
    x2, z = out["x2_hat"][late:], out["z_eq_filtered"][late:]
    return {"d_start": start, "start_error": (start - d_true) / d_true,
            "max_move": float(move[k]), "max_move_at": float(t[i0 + k]),
            "end_move": float((d_hat[-1] - start) / abs(start)),
            "ringdown_move": float((d_hat[i_rest] - start) / abs(start)), "at_rest_move": at_rest,
            "end_error": float((d_hat[-1] - d_true) / d_true),
            "gamma_trace_end": float(out["gamma_trace"][-1]),
            "gamma_trace_max": float(np.max(out["gamma_trace"][i0:])),
            "excitation_end": float(out["excitation"][-1]),
            "theta_std_end": float(out["theta_std[1,2]"][-1]),
            "noise_std_end": float(out["noise_std"][-1]),
            "x2_hat_rms_at_rest": float(np.sqrt(np.mean(x2 ** 2))),
            "z_mean_at_rest": float(np.mean(z)),
            "converged": float(out["converged"][0]),
            "identifier_active": float(out["identifier_active"][0])}


def run_row(variant: str, kind: str, meas_name: str, rest: float, data_dir: Path, fmu: Path,
            overrides: dict[str, float] | None = None) -> dict[str, Any]:
    """Both FMU methods on one measured record (overrides: FMU parameters added to
    fmu-default's, for diagnostic runs)."""
    from harness import identify as ident

    start = time.perf_counter()
    data = plants.Dataset.load(data_path(data_dir, variant, kind))
    meas = sensors.MEASUREMENTS[meas_name]
    # One noise sequence per measurement: the plant kinds and variants see the same one.
    y = sensors.measure(data.x1, meas, sensors.seed_of("no-excitation", meas_name))
    s = SCENARIOS["6.3"]
    c1, c2, c3 = s.c_nominal[:3]
    case = methods.Case(data, y, meas, float(s.observer["b"]), (c1, c2, c3), s.transient)
    d_true = float(data.d[-1])
    results: dict[str, dict[str, object]] = {}
    row: dict[str, Any] = {"variant": variant, "plant": kind, "measurement": meas_name,
                           "d_true": d_true, "at_rest_from": rest, "methods": results}
    for method in methods.FMU_METHODS:
        params = methods.fmu_parameters(case, method)
        if method == "fmu-default":
            params.update(overrides or {})
        try:
            out = ident.identify(ident.Recording(data.t, y, data.u), fmu, params,
                                 input_hold="sampled")
            scores: dict[str, float] | str = quiet_scores(data.t, out, d_true, rest)
            trace = out["theta_hat[1,2]"][::100]  # 100 Hz for the figure
        except Exception as error:  # a failed run is a result, not a crash
            scores, trace = f"{type(error).__name__}: {error}"[:300], np.array([])
        results[method] = {"scores": scores, "d_hat_100hz": trace.tolist()}
    row["seconds"] = round(time.perf_counter() - start, 1)
    return row


# ---- report ---------------------------------------------------------------------------
def pct(x: float) -> str:
    return f"{100 * x:+.2f} %" if math.isfinite(x) else str(x)


def g(x: float) -> str:
    return f"{x:.3g}"


def markdown(rows: list[dict], data_meta: list[dict], fmu_sha: str, runtime: float,
             jobs: int = 2) -> list[str]:
    """The generated document (runtime [s] of the run with that many jobs)."""
    meas_label = {m: sensors.MEASUREMENTS[m].label for m in MEASUREMENTS}
    lines = [
        "# 60 s without excitation after MFF identification, every kind of plant data",
        "",
        "<!-- GENERATED by bench/reports/no_excitation.py: do not edit, re-run the script. -->",
        "",
        f"Generated by `.venv/bin/python -m bench.reports.no_excitation` ({len(rows)} records x 2 "
        f"methods, {runtime:.0f} s with {jobs} job{'s' if jobs != 1 else ''}). "
        "SuperTwistingObserver.fmu SHA-256 "
        f"`{fmu_sha[:16]}`. Deterministic (fixed seeds).",
        "",
        "## Experiment",
        "",
        "* Plant: the paper's 6.3 pendulum, x'' = b u - c1 sin x - c3 sign x' - d x' "
        "(c1 = MgL/(2J), c3 = Ps/J, no viscous friction), from rest at 0. For "
        f"{EXCITED:g} s (the 6.3 record length) the torque is data set A's multi-sine "
        "(bench/reports/realdata/plants.py; swings to about +-0.95 rad); then u = 0 for "
        f"{QUIET:g} s. The pendulum rings down and sticks in static friction "
        "(|c1 sin x| <= c3) about 2 s after the torque stops, and rests.",
        "* Why this is \"no excitation\" for the identifier: the only identified parameter "
        "is d, whose regressor is the velocity. At rest it is 0 and u = 0: the data carry "
        "no information on d, and a correct identifier keeps its estimate. The 2 s "
        "ring-down still carry information, so the true damping is held from the moment "
        "the torque stops: the right answer does not move during the 60 s either.",
        "* Variants: " + "; ".join(f"`{k}`: {v}" for k, v in VARIANTS.items()) + ". The "
        "first is the 6.3 experiment (its d is rising at 0.056/s when the torque stops); "
        "the second has no drift for the MFF drift model to extrapolate.",
        f"* Plant kinds ({RATE // 1000} kHz samples, bench/reports/realdata/plants.py): `accurate` "
        "DOP853 1e-12 with every reversal, the stop and the torque's end located; "
        "`rk45-1e-4`/`rk45-1e-6` RK45 without events, except that the final stop into "
        f"static friction ends it (speed below {plants.STOP_SPEED:g} rad/s inside the "
        "friction band: a solver without events creeps along x' = 0 at steps of 1e-7 s "
        "there); `euler` explicit Euler at the sample step (at rest its velocity "
        "alternates +-h c3 = +-5e-5 rad/s, a limit cycle of the discretization).",
        "* Measurements: " + ", ".join(meas_label.values()) + " (one seed per measurement).",
        "* Methods: `fmu-default` = harness.identify with 6.3's problem statement only "
        "(b, c_nominal, identifier = 2 MFF, identify[2] alone, identify_b off; "
        "bench/reports/realdata/methods.py fmu_parameters) and the torque as `sampled`; "
        "`fmu-paper` adds the paper's method, gains and filter of 6.3 (R = 0.1, "
        "rho = 1e-3).",
        "",
        "## Metrics",
        "",
        f"d_hat = theta_hat[1,2]; d0 = d_hat when the torque stops (t = {EXCITED:g} s). "
        "`max move` = max |d_hat - d0| / d0 over the 60 s and when (`target`: < 1 %, "
        "ring-down included); "
        "`end` = (d_hat(end) - d0)/d0; `ring-down` = the move from d0 to the moment the "
        f"true |x'| stays below {AT_REST_SPEED:g} rad/s (t_rest); `at rest` = max "
        "|d_hat - d_hat(t_rest)| / d0 after it (`target at rest`: < 1 %); `d0 err` = "
        "(d0 - d)/d; trace(Gamma), "
        "`excitation`, `theta_std[1,2]` and `noise_std` at the end; `|x2_hat| rest` = "
        "RMS of the published velocity from t_rest + 1 s (the regressor the identifier "
        "sees at rest; 0 means it sees nothing); `z rest` = mean of z_eq_filtered over "
        "the same span (the perturbation the observer attributes to the resting pendulum).",
        "",
        "## Plant data at rest",
        "",
        "| variant | plant | torque off -> at rest [s] | rest angle [rad] "
        "| creep at rest [rad/s] |",
        "|---|---|---|---|---|",
    ] + [f"| {m['variant']} | {m['plant']} | {m['at_rest_from'] - EXCITED:.2f} "
         f"| {m['rest_angle']:.5f} | {m['creep']:.2g} |" for m in data_meta] + [""]
    head = ("| variant | plant | measurement | method | max move (at s) | end | ring-down | "
            "at rest | d0 err | trace Gamma end (max) | excitation end | theta_std end | "
            "noise_std end | \\|x2_hat\\| rest | z rest | target | target at rest |")
    for variant in VARIANTS:
        lines += [f"## {variant}", "", head, "|" + "---|" * 17]
        for r in rows:
            if r["variant"] != variant:
                continue
            for method, m in r["methods"].items():
                s = m["scores"]
                if isinstance(s, str):
                    lines.append(f"| {variant} | {r['plant']} | {meas_label[r['measurement']]} "
                                 f"| {method} | fail: {s} |" + " |" * 12)
                    continue
                ok = "met" if s["max_move"] < TARGET else "**missed**"
                ok_rest = "met" if s["at_rest_move"] < TARGET else "**missed**"
                lines.append(
                    f"| {variant} | {r['plant']} | {meas_label[r['measurement']]} | {method} "
                    f"| {100 * s['max_move']:.2f} % ({s['max_move_at']:.1f}) "
                    f"| {pct(s['end_move'])} | {pct(s['ringdown_move'])} "
                    f"| {100 * s['at_rest_move']:.2f} % | {pct(s['start_error'])} "
                    f"| {g(s['gamma_trace_end'])} ({g(s['gamma_trace_max'])}) "
                    f"| {g(s['excitation_end'])} | {g(s['theta_std_end'])} "
                    f"| {g(s['noise_std_end'])} | {g(s['x2_hat_rms_at_rest'])} "
                    f"| {g(s['z_mean_at_rest'])} | {ok} | {ok_rest} |")
        lines.append("")
    lines += ["## Summary (fmu-default)", ""] + summary(rows)
    return lines


def summary(rows: list[dict]) -> list[str]:
    """Worst max move per variant and plant kind, for the docs that quote it."""
    out = []
    for variant in VARIANTS:
        for kind in plants.PLANT_KINDS:
            sel = [(r["measurement"], r["methods"]["fmu-default"]["scores"]) for r in rows
                   if r["variant"] == variant and r["plant"] == kind]
            ok = [(m, s) for m, s in sel if not isinstance(s, str)]
            if not ok:
                continue
            worst = max(ok, key=lambda p: p[1]["max_move"])
            rest = max(s["at_rest_move"] for _, s in ok)
            met = sum(s["max_move"] < TARGET for _, s in ok)
            met_rest = sum(s["at_rest_move"] < TARGET for _, s in ok)
            out.append(f"* {variant}, {kind}: target met in {met} of {len(sel)} measurements "
                       f"from the torque's end, in {met_rest} at rest; "
                       f"worst max move {100 * worst[1]['max_move']:.2f} % "
                       f"({sensors.MEASUREMENTS[worst[0]].label}); "
                       f"worst move at rest {100 * rest:.2f} %.")
    return out


def figure(rows: list[dict], path: Path) -> None:
    """d_hat / d0 - 1 of fmu-default over the quiet phase, one panel per measurement."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(VARIANTS), len(MEASUREMENTS), figsize=(15, 6.5), sharex=True,
                             squeeze=False)
    t = np.arange(int(round((EXCITED + QUIET) * 100))) / 100.0
    for i, variant in enumerate(VARIANTS):
        for j, meas in enumerate(MEASUREMENTS):
            ax = axes[i][j]
            for r in rows:
                if r["variant"] != variant or r["measurement"] != meas:
                    continue
                m = r["methods"]["fmu-default"]
                if isinstance(m["scores"], str):
                    continue
                d_hat = np.asarray(m["d_hat_100hz"])
                sel = t[:len(d_hat)] >= EXCITED - 2
                ax.plot(t[:len(d_hat)][sel], 100 * (d_hat[sel] / m["scores"]["d_start"] - 1),
                        label=r["plant"], lw=1)
            ax.axhspan(-100 * TARGET, 100 * TARGET, color="0.9", zorder=0)
            ax.axvline(EXCITED, color="0.5", lw=0.8, ls=":")
            ax.set_title(f"{variant}, {sensors.MEASUREMENTS[meas].label}", fontsize=9)
            if j == 0:
                ax.set_ylabel("d_hat / d0 - 1 [%]")
            if i == len(VARIANTS) - 1:
                ax.set_xlabel("t [s] (torque off at 50 s)")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("fmu-default: the damping estimate after the torque stops (grey: +-1 %)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=None,
                        help="the run's folder and the report's (default build/no_excitation, "
                             "the report then in build/reports)")
    parser.add_argument("--fmu-dir", type=Path, default=REPO / "build" / "fmus")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--plants", default=",".join(plants.PLANT_KINDS))
    parser.add_argument("--measurements", default=",".join(MEASUREMENTS))
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="an FMU parameter for fmu-default (diagnostic runs)")
    args = parser.parse_args(argv)
    variants, kinds, measurements = (args.variants.split(","), args.plants.split(","),
                                     args.measurements.split(","))
    for given, known in ((variants, VARIANTS), (kinds, plants.PLANT_KINDS),
                         (measurements, MEASUREMENTS)):
        if unknown := [x for x in given if x not in known]:
            parser.error(f"unknown {unknown}: expected some of {', '.join(known)}")
    try:
        overrides = {k: float(v) for k, v in (a.split("=", 1) for a in args.set)}
    except ValueError:
        parser.error(f"--set expects NAME=NUMBER, got {args.set}")
    full = (not overrides and variants == list(VARIANTS) and kinds == list(plants.PLANT_KINDS)
            and measurements == list(MEASUREMENTS))
    t_start = time.perf_counter()
    out: Path = args.out or REPO / "build" / "no_excitation"
    reports: Path = args.out or REPORTS
    data_dir = out / "data"
    data_dir.mkdir(parents=True, exist_ok=True)
    src = Path(args.fmu_dir) / "SuperTwistingObserver.fmu"
    if not src.exists():
        print(f"{src} is missing: run ./build.sh fmus", file=sys.stderr)
        return 2
    fmu = out / src.name  # a copy: a rebuild during the run does not mix versions
    shutil.copyfile(src, fmu)
    fmu_sha = hashlib.sha256(fmu.read_bytes()).hexdigest()
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        made = [pool.submit(make_data, v, k, data_dir) for v in variants for k in kinds]
        data_meta = [job.result() for job in made]
        rest = {(m["variant"], m["plant"]): m["at_rest_from"] for m in data_meta}
        print(f"data: {len(made)} trajectories in {time.perf_counter() - t_start:.1f} s",
              file=sys.stderr)
        jobs = [pool.submit(run_row, v, k, meas, rest[v, k], data_dir, fmu, overrides)
                for v in variants for k in kinds for meas in measurements]
        rows = [job.result() for job in jobs]
    runtime = time.perf_counter() - t_start
    shutil.rmtree(data_dir, ignore_errors=True)
    (out / "no_excitation.json").write_text(json.dumps(
        {"fmu_sha256": fmu_sha, "runtime_s": round(runtime, 1), "data": data_meta,
         "overrides": overrides,
         "rows": [{**r, "methods": {k: {"scores": v["scores"]} for k, v in r["methods"].items()}}
                  for r in rows]}, indent=1))
    if not full:  # a diagnostic subset: print it, no report
        for r in rows:
            s = r["methods"]["fmu-default"]["scores"]
            print(f"{r['variant']}, {r['plant']}, {r['measurement']}, fmu-default {overrides}: "
                  + (s if isinstance(s, str) else
                     f"max move {100 * s['max_move']:.2f} %, end {pct(s['end_move'])}, at rest "
                     f"{100 * s['at_rest_move']:.2f} %, d0 err {pct(s['start_error'])}, "
                     f"trace Gamma end {g(s['gamma_trace_end'])}"))
        return 0
    reports.mkdir(parents=True, exist_ok=True)
    document = markdown(rows, data_meta, fmu_sha, runtime, max(1, args.jobs))
    (reports / "no_excitation.md").write_text("\n".join(document) + "\n")
    figure(rows, reports / "no_excitation.png")
    print("\n".join(summary(rows)), file=sys.stderr)
    print(f"{len(rows)} records in {runtime:.1f} s; wrote {reports / 'no_excitation.md'}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
