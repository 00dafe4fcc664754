"""The generated results document of bench/reports/robots.py (build/reports/robots_results.md):
conditions, the issue's targets judged from the rows, one table per sampling rate."""
from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from bench.reports.realdata.report import fmt

Row = dict  # one entry of the results JSON's "rows"

BASELINE = "SG+LS"  # the offline baseline the torque prediction is held against
TORQUE_ROBOTS = ("double_pendulum", "ur5")  # the torque target's robots (the Panda: reported)
LIMITS = {"torque": {"exact": 0.01, "17 bit": 0.03},
          "payload": {"exact": 0.005, "17 bit": 0.005},
          "friction": {"exact": 0.01, "17 bit": 0.03}}
METHOD_NOTES = {
    "sg": "pipeline, Savitzky-Golay (offline)",
    "observer": "pipeline, causal observer",
    "SG+LS": "baseline: SG + least squares",
    "model obs (URDF)": "model-based observer, URDF model",
    "model obs (ident.)": "model-based observer, identified model",
    "model obs (ident. sign)": "the same, sign(q') Coulomb",
    "FMU": "RobotObserver FMU (qd_hat)",
}


def _nan(x: float | None) -> float:
    return float("nan") if x is None else float(x)


def velocity_ratio(row: Row) -> float:
    """The worst joint's velocity RMS over the causal Kalman filter's on that joint."""
    return max(v / k for v, k in zip(row["velocity_rms_joints"], row["kalman_rms_joints"]))


def friction(row: Row) -> float:
    return max(row["viscous"], row["coulomb"])


def _where(row: Row) -> str:
    return f"{row['robot']}, {row['rate'] / 1000:g} kHz, {row['encoder']}"


def _pct(x: float, digits: int = 3) -> str:
    return "-" if math.isnan(x) else f"{100 * x:.{digits}f} %"


def judge(rows: Sequence[Row]) -> list[dict]:
    """Per target and method (the baseline excluded): the worst figure over the rows the
    target covers, where it was measured, and whether the target is met there.
    Keys: target, method, figure (text), where, met (True/False), rows (count)."""
    out = []
    methods = list(dict.fromkeys(r["method"] for r in rows if r["method"] != BASELINE))
    by_row = {(r["robot"], r["rate"], r["encoder"], r["method"]): r for r in rows}

    def worst(chosen: list[Row], key, limit) -> tuple[Row, float, bool]:
        """The row of the largest key(row) / limit(row) and whether every row is within."""
        scored = [(key(r) / limit(r), r) for r in chosen]
        ratio, row = max(scored, key=lambda s: s[0])
        return row, key(row), all(s <= 1.0 for s, _ in scored)

    for method in methods:
        mine = [r for r in rows if r["method"] == method]
        # torque prediction on the validation trajectory, the two-link arm and the UR5
        torque = [r for r in mine if r["robot"] in TORQUE_ROBOTS]
        for encoder in ("exact", "17 bit"):
            chosen = [r for r in torque if r["encoder"] == encoder]
            if chosen:
                row, value, met = worst(chosen, lambda r: r["prediction"],
                                        lambda r: LIMITS["torque"][r["encoder"]])
                out.append({"target": f"torque prediction <= {_pct(LIMITS['torque'][encoder], 0)}"
                            f" ({encoder}; double pendulum, UR5)", "method": method,
                            "figure": _pct(value), "where": _where(row), "met": met,
                            "rows": len(chosen)})
        # no worse than the offline baseline, row by row
        found = [(r, by_row.get((r["robot"], r["rate"], r["encoder"], BASELINE))) for r in torque]
        pairs = [(r, b) for r, b in found if b is not None]
        if pairs:
            row, base = max(pairs, key=lambda p: p[0]["prediction"] / p[1]["prediction"])
            met = all(r["prediction"] <= b["prediction"] for r, b in pairs)
            out.append({"target": f"torque prediction no worse than {BASELINE} (double pendulum, "
                        "UR5)", "method": method,
                        "figure": f"x{fmt(row['prediction'] / base['prediction'])} "
                                  f"({_pct(row['prediction'])} vs {_pct(base['prediction'])})",
                        "where": _where(row), "met": met, "rows": len(pairs)})
        panda = [r for r in mine if r["robot"] not in TORQUE_ROBOTS]
        for encoder in ("exact", "17 bit"):
            chosen = [r for r in panda if r["encoder"] == encoder]
            if chosen:
                row = max(chosen, key=lambda r: r["prediction"])
                out.append({"target": f"torque prediction, reported ({encoder}; "
                            f"{', '.join(sorted({r['robot'] for r in chosen}))})",
                            "method": method, "figure": _pct(row["prediction"]),
                            "where": _where(row), "met": None, "rows": len(chosen)})
        payload = [r for r in mine if not math.isnan(_nan(r["payload"]))]
        if payload:
            row, value, met = worst(payload, lambda r: r["payload"],
                                    lambda r: LIMITS["payload"][r["encoder"]])
            out.append({"target": "payload mass within 0.5 %", "method": method,
                        "figure": _pct(value), "where": _where(row), "met": met,
                        "rows": len(payload)})
        for encoder in ("exact", "17 bit"):
            chosen = [r for r in mine if r["encoder"] == encoder]
            if chosen:
                limit = LIMITS["friction"][encoder]
                row, value, met = worst(chosen, friction, lambda r: limit)  # noqa: B023 (called in this iteration)
                kind = "viscous" if row["viscous"] >= row["coulomb"] else "Coulomb"
                out.append({"target": f"friction per joint within {_pct(limit, 0)} ({encoder})",
                            "method": method, "figure": f"{_pct(value, 2)} ({kind})",
                            "where": _where(row), "met": met, "rows": len(chosen)})
        for encoder in ("exact", "17 bit"):
            chosen = [r for r in mine if r["encoder"] == encoder]
            if chosen:
                row, value, met = worst(chosen, velocity_ratio, lambda r: 1.0)
                out.append({"target": "velocity RMS <= the causal Kalman filter's, worst "
                            f"joint's ratio ({encoder})", "method": method,
                            "figure": f"x{value:.3f}", "where": _where(row), "met": met,
                            "rows": len(chosen)})
    return out


def targets_table(rows: Sequence[Row]) -> list[str]:
    """The judged targets: a table of targets by methods (worst figure and verdict), a
    line per target naming the methods that meet it, and where each worst figure is."""
    judged = judge(rows)
    methods = list(dict.fromkeys(j["method"] for j in judged))
    targets = list(dict.fromkeys(j["target"] for j in judged))
    cell = {(j["target"], j["method"]): j for j in judged}

    def verdict(j: dict) -> str:
        return "" if j["met"] is None else (" met" if j["met"] else " **missed**")

    lines = ["| target | " + " | ".join(f"`{m}`" for m in methods) + " |",
             "|---|" + "---|" * len(methods)]
    for target in targets:
        lines.append(f"| {target} | " + " | ".join(
            f"{cell[target, m]['figure']}{verdict(cell[target, m])}" if (target, m) in cell
            else "-" for m in methods) + " |")
    lines.append("")
    for target in targets:
        mine = [cell[target, m] for m in methods if (target, m) in cell]
        if mine[0]["met"] is None:
            continue
        met = [j["method"] for j in mine if j["met"]]
        missed = [j["method"] for j in mine if not j["met"]]
        lines.append(f"* {target}: met by {', '.join(f'`{m}`' for m in met) or 'none'}"
                     + (f"; missed by {', '.join(f'`{m}`' for m in missed)}" if missed else "")
                     + ".")
    lines += ["", "Where each worst figure is (robot, rate, encoder; of how many rows):", "",
              "| target | " + " | ".join(f"`{m}`" for m in methods) + " |",
              "|---|" + "---|" * len(methods)]
    for target in targets:
        lines.append(f"| {target} | " + " | ".join(
            f"{cell[target, m]['where']} ({cell[target, m]['rows']})" if (target, m) in cell
            else "-" for m in methods) + " |")
    return lines


def rate_table(rows: Sequence[Row]) -> list[str]:
    """One rate's rows: per robot and encoder the methods and the Kalman filter side by
    side, the best figure of each group in bold (ties as printed all bold)."""
    head = ["robot", "encoder", "method", "velocity RMS [rad/s] (max over joints)",
            "velocity / Kalman (worst joint)", "torque prediction error", "payload mass error",
            "viscous error (max)", "Coulomb error (max)", "time [s]"]
    shown = {"velocity_rms": fmt, "prediction": _pct, "payload": _pct,
             "viscous": lambda x: _pct(x, 2), "coulomb": lambda x: _pct(x, 2)}
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    groups = list(dict.fromkeys((r["robot"], r["encoder"]) for r in rows))
    for robot, encoder in groups:
        group = [r for r in rows if (r["robot"], r["encoder"]) == (robot, encoder)]
        kalman = {"velocity_rms": group[0]["kalman_rms"]}
        best = {}
        for key, show in shown.items():
            values = [_nan(r[key]) for r in group] + ([kalman[key]] if key in kalman else [])
            finite = [v for v in values if not math.isnan(v)]
            best[key] = show(min(finite)) if len(finite) > 1 else None

        def cell(values: dict, key: str) -> str:
            text = shown[key](_nan(values[key]))
            return f"**{text}**" if text == best[key] else text  # noqa: B023 (called in this iteration)

        for r in group:
            lines.append("| " + " | ".join([
                robot, encoder, r["method"], cell(r, "velocity_rms"), f"{velocity_ratio(r):.3f}",
                cell(r, "prediction"), cell(r, "payload"), cell(r, "viscous"),
                cell(r, "coulomb"), f"{r['seconds']:.1f}"]) + " |")
        lines.append(f"| {robot} | {encoder} | Kalman (causal, oracle) | "
                     f"{cell(kalman, 'velocity_rms')} | 1.000 | - | - | - | - | - |")
    return lines


def gains_table(rows: Sequence[Row]) -> list[str]:
    """The model-based observer's tuned gains and Coulomb shape per condition."""
    chosen = [r for r in rows if r["method"] == "model obs (ident.)" and r.get("tuned")]
    if not chosen:
        return []
    lines = ["| robot | rate | encoder | alpha1 | alpha2 | v_s [rad/s] |", "|---|---|---|---|---|---|"]
    for r in chosen:
        a1, a2, vs = r["tuned"]
        lines.append(f"| {r['robot']} | {r['rate'] / 1000:g} kHz | {r['encoder']} | {fmt(a1)} | "
                     f"{fmt(a2)} | {vs:g} |")
    return lines


def left_out(run: dict) -> list[str]:
    """The requested (robot, rate) cases and methods that have no rows."""
    have = {(r["robot"], r["rate"], r["method"]) for r in run["rows"]}
    out = []
    for robot in run["robots"]:
        for rate in run["rates"]:
            missing = [m for m in run["methods"] if (robot, rate, m) not in have]
            if missing:
                why = "left out (`--model-left-out`)" if f"{robot}@{rate:g}" in \
                    run["model_left_out"] else "not run (the run stopped before)"
                out.append(f"{robot} at {rate / 1000:g} kHz: {', '.join(missing)}: {why}")
    return out


def header(run: dict) -> list[str]:
    """Title, provenance and conditions."""
    sha = run.get("fmu_sha256")
    fmu = (f" RobotObserver.fmu SHA-256 `{sha[:16]}` (the FMU at `build/fmus` when the run "
           "started, copied for the run)." if sha else "")
    seconds = run["seconds"]
    lines = [
        "# Serial robots: bench results",
        "",
        "<!-- GENERATED by bench/reports/robots.py: do not edit, re-run the script. -->",
        "",
        f"Generated by `{run['command']}` at commit `{run['commit']}`.{fmu} "
        f"Run time {run.get('runtime_s', float('nan')):.0f} s with one process on a shared "
        f"2-core machine (load average {run['load_start']:.1f} at the start, "
        f"{run.get('load_end', float('nan')):.1f} at the end). Every figure except the "
        "times is deterministic (fixed seeds); the times are wall times under that load. "
        "Explanations of the methods and of what limits them: "
        "[docs/robots.md](../../docs/robots.md).",
        "",
        "## Conditions",
        "",
        "* Robots (example-robot-data URDFs): the two-link arm (double pendulum) with an "
        "unknown 0.3 kg tip payload (unknown: the payload and the friction); the UR5 and the "
        "Panda arm (fingers locked) with every base parameter and the friction unknown (the "
        "truth: the URDF's link parameters scaled by 0.8..1.2 per link). Friction per joint "
        "viscous + Coulomb, the Coulomb term saturated below 0.02 rad/s in the truth.",
        f"* Data: Pinocchio forward dynamics (pin.aba), DOP853 rtol 1e-10, PD control with "
        f"gravity compensation along a multi-sine; training log {seconds:g} s sampled at the "
        f"rate, seed {run['seed']}; validation trajectory {seconds / 2:g} s at 1 kHz, seed "
        f"{run['seed'] + 100}. Encoders: exact, or 17 bits per turn (rounding).",
        f"* Rates: {', '.join(f'{r / 1000:g} kHz' for r in run['rates'])}; robots: "
        f"{', '.join(run['robots'])}.",
    ]
    gaps = left_out(run)
    lines.append("* Rows left out: " + ("; ".join(gaps) + "." if gaps else "none."))
    lines += [
        "",
        "## Methods",
        "",
        "* `sg`: the identification pipeline (`harness.robot.pipeline.identify_robot`, "
        "`python -m harness identify --robot`) with zero-phase Savitzky-Golay derivatives "
        "(0.05 s): offline.",
        "* `observer`: the same pipeline with `--velocity observer`: the causal model-free "
        "observer bank per joint and the momentum-form regression.",
        "* `SG+LS`: the offline baseline: plain Savitzky-Golay (0.05 s) + torque-space least "
        "squares over the base parameters, every equation, no consistency step.",
        "* `model obs (ident.)`: the model-based observer of the RobotObserver FMU (its C core "
        "through ctypes) with the model `sg` identified from the same log, the online LSM "
        "identifier over the base parameters on top (from 0.2 s); gains and Coulomb shape "
        "tuned on the truth (oracle; table at the end). `model obs (URDF)`: with the URDF's "
        "model; `model obs (ident. sign)`: with the sign(q') Coulomb shape.",
        "* `FMU`: the RobotObserver FMU (FMI 2, fmpy, one doStep per sample) with the "
        "settings of `model obs (ident.)`, scored on `qd_hat` after doStep(t_k, h), its "
        "prediction for t_k + h, against the velocity there.",
        "* Kalman (causal, oracle): a steady-state constant-acceleration Kalman filter per "
        "joint on the same samples, its lambda tuned per joint for the least velocity RMS "
        "against the truth (10^-18..10^0).",
        "",
        "## Metrics",
        "",
        "* Velocity RMS error per joint after 0.5 s, for the methods also before the last "
        "0.5 s (Savitzky-Golay's edge), for the Kalman filter to the end; the tables show the "
        "largest over the joints and the worst joint's ratio to the Kalman filter's RMS on "
        "the same joint (the velocity target's figure).",
        "* Torque prediction error: RMS(Y(q, q', q'') pi_hat - tau) / RMS(tau) on the "
        "validation trajectory, true states, the truth's Coulomb shape: the identified "
        "parameters are scored, not the velocities.",
        "* Payload mass error relative to the 0.3 kg payload (double pendulum); friction "
        "errors relative to the truth, the largest over the joints.",
        "* Time: the method's wall time on the training log (for the model-based observer "
        "its gain tuning included, the `sg` identification of its model not).",
    ]
    return lines


def write_document(path: Path, run: dict) -> None:
    """The whole document from a results JSON (bench/reports/robots.py --results)."""
    rows = [dict(r) for r in run["rows"]]
    for r in rows:
        r["payload"] = _nan(r["payload"])
    details = header(run)
    split = details.index("## Conditions")  # the targets first: what a reader looks for
    lines = details[:split]
    lines += ["## Against the issue's targets", "",
              "Computed from the tables below: for each method the worst figure over the rows "
              "the target covers (both rates, the robots named), `met` if every such row is "
              "within the limit. The cost target (a 7-joint internal step <= 20 us) is not "
              "measured by this script: `python -m bench.perf.robot_step_cost`, "
              "[docs/design/performance.md](../../docs/design/performance.md).", ""]
    lines += targets_table(rows) + [""] + details[split:]
    for rate in sorted({r["rate"] for r in rows}):
        chosen = [r for r in rows if r["rate"] == rate]
        lines += ["", f"## {rate / 1000:g} kHz", "",
                  "Best figure per robot and encoder in bold.", ""]
        lines += rate_table(chosen)
    gains = gains_table(rows)
    if gains:
        lines += ["", "## The model-based observer's tuned gains (one pair for all joints)", ""]
        lines += gains
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")
