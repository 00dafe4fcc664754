"""The generated markdown report (tables, summary) and the figure."""
from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Sequence
from pathlib import Path

from .methods import BASELINE_METHODS, METHODS
from .sensors import measurement, model_error

Row = dict  # one entry of results.json "rows"

# (metric, title, which rows have it); lower is better for every metric.
TABLES: list[tuple[str, str, Callable[[Row], bool]]] = [
    ("vel_rms", "Velocity RMS error [rad/s] after the transient", lambda r: True),
    ("vel_max", "Velocity max error [rad/s] after the transient", lambda r: True),
    ("param_worst", "Worst relative error of c1, c2, c3 at the end", lambda r: r["kind"] == "lsm"),
    ("t1pct_worst", "Time [s] after which c1, c2, c3 all stay within 1 % (inf: not by the end)",
     lambda r: r["kind"] == "lsm"),
    ("err_b", "Relative error of b at the end (fmu: b_hat if the FMU identifies b, else "
     "not estimated)", lambda r: r["kind"] == "lsm"),
    ("pert_rms", "6.1: RMS(zbar - xi) [rad/s^2] after the transient",
     lambda r: r["kind"] == "perturbation"),
    ("pert_delay", "6.1: delay [s] of zbar behind xi (harness.metrics.best_shift)",
     lambda r: r["kind"] == "perturbation"),
    ("d_rms", "6.3: RMS(d_hat - d) [1/s] after 5 s", lambda r: r["kind"] == "mff"),
    ("d_lag", "6.3: lag [s] of d_hat behind d", lambda r: r["kind"] == "mff"),
    ("tv_zbar", "Chattering: total variation of zbar per second [rad/s^3]", lambda r: True),
]
SUMMARY_METRICS = ("vel_rms", "param_worst", "pert_rms", "d_rms")


def value(row: Row, method: str, metric: str) -> float:
    """One score of one method in one row (NaN when absent)."""
    v = row["methods"][method]["scores"].get(metric)
    return float("nan") if v is None else float(v)


def fmt(x: float) -> str:
    """Three significant digits; "-" for NaN."""
    if math.isnan(x):
        return "-"
    if math.isinf(x):
        return "inf"
    if x == 0:
        return "0"
    if 0.01 <= abs(x) < 1000:
        return f"{x:.3g}"
    return f"{x:.2e}"


def row_label(row: Row) -> list[str]:
    """The condition columns of a row."""
    model = "scenario" if row["model"] == "scenario" else model_error(row["model"]).label
    return [row["dataset"], row["plant"], f"{row['rate'] // 1000} kHz",
            measurement(row["measurement"]).label, model]


def short_label(row: Row) -> str:
    """The condition as one line."""
    return " / ".join(row_label(row))


def table(rows: Sequence[Row], metric: str) -> list[str]:
    """One markdown table of a metric: a row per condition, a column per method."""
    head = ["data", "plant", "rate", "measurement", "nominal", *METHODS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        values = [value(row, m, metric) for m in METHODS]
        finite = [v for v in values if not math.isnan(v)]
        best = min(finite) if finite else None
        cells = []
        for m, v in zip(METHODS, values):
            text = "fail" if math.isnan(v) and row["methods"][m].get("error") else fmt(v)
            # ties within 0.1 % are all bold (e.g. the Euler rows, where every method
            # meets the same floor)
            tie = best is not None and len(finite) > 1 and v <= best + 1e-3 * abs(best)
            cells.append(f"**{text}**" if tie else text)
        lines.append("| " + " | ".join(row_label(row) + cells) + " |")
    return lines


def _ratios(rows: Sequence[Row], metric: str, other: Callable[[Row], float]) -> list[float]:
    """fmu-default / other per row, where both are finite."""
    out = []
    for row in rows:
        a, b = value(row, "fmu-default", metric), other(row)
        if math.isfinite(a) and math.isfinite(b) and b > 0:
            out.append(a / b)
    return out


def best_baseline(row: Row, metric: str) -> tuple[str, float]:
    """(method, score) of the best baseline in a row."""
    pairs = [(m, value(row, m, metric)) for m in BASELINE_METHODS]
    pairs = [p for p in pairs if not math.isnan(p[1])]
    return min(pairs, key=lambda p: p[1]) if pairs else ("-", float("nan"))


def summary(rows: Sequence[Row]) -> list[str]:
    """Median ratios and the rows where fmu-default is beaten."""
    lines = ["Medians over the rows of the ratio of fmu-default's score to the other's "
             "(below 1: fmu-default is better; rows where either failed are left out).", "",
             "| metric | rows | fmu-default / best baseline | fmu-default / kalman (causal) | "
             "fmu-default / fmu-paper |", "|---|---|---|---|---|"]
    for metric in SUMMARY_METRICS:
        have = [r for r in rows if metric in r["methods"]["fmu-default"]["scores"]]
        if not have:
            continue
        ratios = [_ratios(have, metric, lambda r: best_baseline(r, metric)[1]),  # noqa: B023 (called in this iteration)
                  _ratios(have, metric, lambda r: value(r, "kalman", metric)),  # noqa: B023 (called in this iteration)
                  _ratios(have, metric, lambda r: value(r, "fmu-paper", metric))]  # noqa: B023 (called in this iteration)
        cells = [f"{fmt(statistics.median(x))} ({len(x)})" if x else "-" for x in ratios]
        lines.append(f"| {metric} | {len(have)} | " + " | ".join(cells) + " |")
    lines += ["", "Rows where fmu-default is not the best (metric: fmu-default vs the best "
              "other method, ratio):", ""]
    lost = 0
    for row in rows:
        parts = []
        for metric in SUMMARY_METRICS:
            if metric not in row["methods"]["fmu-default"]["scores"]:
                continue
            mine = value(row, "fmu-default", metric)
            others = [(m, value(row, m, metric)) for m in METHODS if m != "fmu-default"]
            others = [o for o in others if not math.isnan(o[1])]
            if not others:
                continue
            m, best = min(others, key=lambda o: o[1])
            if math.isnan(mine) or best < mine:
                ratio = "failed" if math.isnan(mine) else \
                    ("x" + fmt(mine / best) if best > 0 else "inf")
                parts.append(f"{metric} {fmt(mine)} vs {m} {fmt(best)} ({ratio})")
        if parts:
            lost += 1
            lines.append(f"* {short_label(row)}: " + "; ".join(parts))
    if not lost:
        lines.append("* none")
    return lines


def tuning_table(rows: Sequence[Row]) -> list[str]:
    """The knob each baseline was given per row."""
    lines = ["| data | plant | rate | measurement | nominal | kalman q | rts q | savgol window |",
             "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        tun = {m: row["methods"][m].get("tuning", {}) for m in BASELINE_METHODS}
        w = tun["savgol"].get("window")
        cells = [fmt(tun["kalman"].get("q", float("nan"))), fmt(tun["rts"].get("q", float("nan"))),
                 f"{w} ({fmt(tun['savgol']['window_s'])} s)" if w else "-"]
        lines.append("| " + " | ".join(row_label(row) + cells) + " |")
    return lines


def failures(rows: Sequence[Row]) -> list[str]:
    """Every failed run with the first line of its error."""
    out = []
    for row in rows:
        for m in METHODS:
            err = row["methods"][m].get("error")
            if err:
                out.append(f"* {short_label(row)}, {m}: `{err.splitlines()[0][:300]}`")
    return out or ["* none"]


def write_markdown(path: Path, rows: Sequence[Row], header: Sequence[str]) -> None:
    """The whole document: header, summary, one table per metric, tuning, failures."""
    lines = list(header)
    lines += ["", "## Summary", ""] + summary(rows)
    for metric, title, which in TABLES:
        chosen = [r for r in rows if which(r)]
        if chosen:
            lines += ["", f"## {title}", "", f"Metric `{metric}`; best per row in bold.", ""]
            lines += table(chosen, metric)
    lines += ["", "## Baseline tuning chosen per row (oracle: best velocity RMS)", ""]
    lines += tuning_table(rows)
    lines += ["", "## Failed runs", ""] + failures(rows)
    path.write_text("\n".join(lines) + "\n")


def write_figure(path: Path, rows: Sequence[Row], datasets: Sequence[str] = ("A",),
                 model: str = "b-exact") -> None:
    """Velocity RMS and worst parameter error against the measurement error level, one
    row of panels per data set (accurate plant, the given nominal model): 1 kHz solid,
    10 kHz dashed (other rates are in the tables), encoders as open markers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    floor = 3e-8  # where "noise-free" is drawn on the log axis
    colors = dict(zip(METHODS, ["C3", "C1", "C0", "C2", "C4"]))
    fig, axes = plt.subplots(len(datasets), 2, figsize=(12, 4.6 * len(datasets)), squeeze=False)
    for panels, name in zip(axes, datasets):
        for ax, metric, ylabel in ((panels[0], "vel_rms", "velocity RMS error [rad/s]"),
                                   (panels[1], "param_worst", "worst relative error of c1..c3")):
            for rate, style in ((1000, "-"), (10000, "--")):
                sel = [r for r in rows if r["dataset"] == name and r["plant"] == "accurate"
                       and r["rate"] == rate and r["model"] == model]
                gauss = sorted((r for r in sel if not measurement(r["measurement"]).bits),
                               key=lambda r: measurement(r["measurement"]).level)
                enc = [r for r in sel if measurement(r["measurement"]).bits]
                for m in METHODS:
                    xs = [max(measurement(r["measurement"]).level, floor) for r in gauss]
                    ys = [value(r, m, metric) for r in gauss]
                    if xs:
                        ax.plot(xs, ys, style, marker="o", ms=3, color=colors[m],
                                label=f"{m} {rate // 1000} kHz")
                    for r in enc:
                        ax.plot(measurement(r["measurement"]).level, value(r, m, metric),
                                "s" if rate == 1000 else "D", mfc="none", color=colors[m])
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("measurement error std [rad] (noise-free at the left edge; "
                          "open markers: encoders)", fontsize=8)
            ax.set_ylabel(ylabel)
            ax.grid(True, which="both", alpha=0.3)
        panels[0].set_title(f"{name}, open loop, accurate plant: velocity")
        panels[1].set_title(f"{name}, {model_error(model).label}: parameters")
        panels[0].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
