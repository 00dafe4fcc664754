"""What a sweep reports besides its table: summary.json (counts, rate, the best run
per headline metric) and one figure per swept parameter."""
from __future__ import annotations

import math
import sys
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from ..json_files import strict_json
from ..outputs import write_atomically
from .plan import SweepSpec


class ProgressLine:
    """Runs done, failed, rate and time left on stderr (tqdm; on a file or pipe at most
    one update per 10 s)."""

    def __init__(self, label: str, total: int, stream=None):
        from tqdm import tqdm

        stream = stream or sys.stderr
        tty = hasattr(stream, "isatty") and stream.isatty()
        self.failed = 0
        self.bar = tqdm(total=total, desc=label, file=stream, disable=False,
                        mininterval=0.2 if tty else 10.0, postfix="0 failed",
                        bar_format="{desc}: {n}/{total} runs, {postfix}, {rate_fmt}, "
                                   "{remaining} left", unit="run")

    def update(self, failed: bool) -> None:
        self.failed += failed
        self.bar.set_postfix_str(f"{self.failed} failed", refresh=False)
        self.bar.update(1)
        if self.bar.n >= self.bar.total:
            self.bar.close()


def headline_metrics(spec: SweepSpec, rows: list[dict[str, Any]]) -> list[str]:
    from ..compare import HEADLINE
    from ..scenarios import SCENARIOS

    present = {k for r in rows for k in r}
    return [m for m in HEADLINE[SCENARIOS[spec.scenario].kind] if m in present]


def write_summary(spec: SweepSpec, rows: list[dict[str, Any]], out: Path, *, resumed: int,
                   executed: int, wall: float, workers: int) -> None:
    ok = [r for r in rows if r.get("status") == "ok"]
    best = {}
    for metric in headline_metrics(spec, rows):
        values = [(r[metric], r) for r in ok if _is_number(r.get(metric))
                  and math.isfinite(r[metric])]
        if values and metric != "delay" and metric != "damping_lag":
            value, r = min(values, key=lambda x: abs(x[0]))
            best[metric] = {"value": value, "key": r["key"],
                            "params": {p: r.get(p) for p in spec.swept}}
    summary = {"scenario": spec.scenario, "stop_time": spec.stop_time, "method": spec.method,
               "runs": len(rows), "ok": len(ok), "failed": len(rows) - len(ok),
               "resumed": resumed, "executed": executed, "wall_time": wall,
               "runs_per_second": executed / wall if wall > 0 else None, "workers": workers,
               "swept": spec.swept, "best": best}
    text, _ = strict_json(summary, default=str)  # a metric never reached: null
    write_atomically(out / "summary.json", lambda path: Path(path).write_text(text))


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float))  # bool included


def _filename(name: str) -> str:
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in name).strip("_")


def plot_summary(spec: SweepSpec, rows: list[dict[str, Any]], out: Path) -> list[Path]:
    """One figure per swept parameter: each headline metric against it (ok runs as
    dots, coloured by noise level if the noise is swept too; the median per
    distinct value as a line; failed runs as red marks on the axis)."""
    from matplotlib.figure import Figure  # no pyplot: the backend of a session stays

    metrics = headline_metrics(spec, rows)
    swept = [p for p in spec.swept if p != "seed"] or spec.swept
    paths: list[Path] = []
    if not metrics:
        return paths
    for param in swept:
        if len({r[param] for r in rows if _is_number(r.get(param))}) < 2:
            continue  # nothing to plot against
        ncols = min(3, len(metrics))
        nrows = (len(metrics) + ncols - 1) // ncols
        fig = Figure(figsize=(4.2 * ncols, 3.2 * nrows + 0.4), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False)
        # Colour by noise level when the noise is swept too (the runs differ most by it).
        levels = sorted({r["noise_std"] for r in rows if _is_number(r.get("noise_std"))})
        by_noise = param != "noise_std" and "noise_std" in spec.swept and 1 < len(levels) <= 6
        for ax, metric in zip(axes.flat, metrics):
            points = [(float(r[param]), float(r[metric]), r.get("noise_std")) for r in rows
                      if r.get("status") == "ok" and _is_number(r.get(param))
                      and _is_number(r.get(metric)) and math.isfinite(r[metric])]
            bad = [float(r[param]) for r in rows
                   if r.get("status") != "ok" and _is_number(r.get(param))]
            groups = ([(f"noise {level:g}", level) for level in levels] if by_noise
                      else [("runs", None)])
            all_x: list[float] = []
            all_y: list[float] = []
            for i, (label, level) in enumerate(groups):
                chosen = [(x, y) for x, y, n in points if level is None or n == level]
                if not chosen:
                    continue
                x, y = (np.array(v) for v in zip(*chosen))
                all_x += list(x)
                all_y += list(y)
                ax.plot(x, y, "o", ms=3, alpha=0.6, color=f"C{i}", label=label)
                distinct = np.unique(x)
                if 1 < len(distinct) <= 25 and len(distinct) < len(x):
                    ax.plot(distinct, [np.median(y[x == v]) for v in distinct], "-",
                            color=f"C{i}", lw=1.5)
            if all_x:
                _scale(ax, "x", np.array(all_x + bad))
                _scale(ax, "y", np.array(all_y))
            if bad:
                ax.plot(bad, [0.0] * len(bad), "x", color="red", transform=ax.get_xaxis_transform(),
                        clip_on=False, label=f"failed ({len(bad)})")
            ax.set_xlabel(param)
            ax.set_ylabel(f"{metric} [{metric_unit(metric)}]")
            ax.grid(True, alpha=0.3)
            if points or bad:
                ax.legend(fontsize=7)
        for ax in list(axes.flat)[len(metrics):]:
            ax.set_visible(False)
        n_ok = sum(r.get("status") == "ok" for r in rows)
        fig.suptitle(f"{spec.scenario} ({spec.stop_time:g} s, {spec.method}): {n_ok} ok, "
                     f"{len(rows) - n_ok} failed of {len(rows)} runs", fontsize=10)
        path = out / f"sweep_{_filename(param)}.png"
        write_atomically(path, partial(fig.savefig, format="png", dpi=100, bbox_inches="tight"))
        paths.append(path)
    return paths


METRIC_UNITS = {"rms_perturbation": "rad/s²", "delay": "s", "max_e2_after_1s": "rad/s",
                "convergence_time": "s", "rms_damping": "1/s", "damping_lag": "s",
                "max_e1_after_1s": "rad", "mean_e2_after_1s": "rad/s"}


def metric_unit(metric: str) -> str:
    """The unit of a harness.metrics.score metric (relative errors: 1)."""
    return METRIC_UNITS.get(metric, "1" if "rel_error" in metric else "?")


def _scale(ax, axis: str, values: np.ndarray) -> None:
    """Log scale when the values are positive and span a decade or more;
    symlog when there are zeros besides such positive values (noise_std = 0)."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    positive = values[values > 0]
    setter = ax.set_xscale if axis == "x" else ax.set_yscale
    if len(positive) < 2 or np.any(values < 0) or positive.max() / positive.min() < 9.99:
        ax.ticklabel_format(axis=axis, style="sci", scilimits=(-3, 4), useOffset=False)
        return
    if np.any(values == 0):
        setter("symlog", linthresh=positive.min())
    else:
        setter("log")

