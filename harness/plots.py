"""Figures of a scenario run (matching the paper's figures 1-6) and of an identification.

Figures are made with :class:`matplotlib.figure.Figure` and saved to files: no
pyplot state and no backend switch, so importing this module changes nothing
in a notebook or GUI session.
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure

from .master import Records
from .metrics import true_perturbation
from .scenarios import Scenario

PAPER_FIGURE = {("6.1-sine", "perturbation"): 1, ("6.1-square", "perturbation"): 2,
                ("6.2", "errors"): 3, ("6.2", "parameters"): 4, ("6.3", "errors"): 5,
                ("6.3", "parameters"): 6}
# The joint basis [sin x1, x2, sign x2, x1, 1]: its coefficients' names and units.
COEFFICIENTS = [("a1 = MgL/(2J)", "1/s²"), ("a2 = Vs/J", "1/s"), ("a3 = Ps/J", "rad/s²"),
                ("c4", "1/s²"), ("c5", "rad/s²")]
TRUE_STYLE: dict[str, Any] = {"color": "k", "ls": "--", "lw": 1.0, "zorder": 3}
NOMINAL_STYLE = {"color": "0.5", "ls": ":", "lw": 1.2, "zorder": 2}
_FAINT_C0 = tuple(0.3 * c + 0.7 for c in to_rgb("C0"))  # C0 at alpha 0.3 on white (see save)


def _title(s: Scenario, what: str, text: str) -> str:
    figure = PAPER_FIGURE.get((s.name, what))
    return f"{text}\n(cf. paper figure {figure})" if figure else text


def save(fig: Figure, path: Path, dpi: int = 110) -> Path:
    """Lays the figure out (nothing clipped) and writes it.

    Agg draws a line of many points in pieces of 5000: drawn whole, a dense line
    (an oscillating estimate over a 10^4 s log) took 180 MB (bench/perf/identify_long_log.py).
    The joints of the pieces are invisible on opaque lines; a translucent line would
    show them darker, so the faint lines are drawn in their blended colour instead."""
    from matplotlib import rc_context

    with rc_context({"agg.path.chunksize": 5000}):
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return path


def plot_errors(s: Scenario, r: Records, out: Path) -> Path:
    t = r.time
    fig = Figure(figsize=(8, 5.5), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    axes[0].plot(t, r["plant.theta"] - r["observer.x1_hat[1]"], lw=0.6)
    axes[0].set_ylabel("x1 - x1_hat [rad]")
    axes[1].plot(t, r["plant.omega"] - r["observer.x2_hat[1]"], lw=0.6)
    axes[1].set_ylabel("x2 - x2_hat [rad/s]")
    axes[1].set_xlabel("t [s]")
    axes[0].set_title(_title(s, "errors", f"{s.title}: estimation errors"), fontsize=10)
    inset = axes[1].inset_axes([0.55, 0.55, 0.42, 0.4])
    late = t >= 1.0
    inset.plot(t[late], (r["plant.omega"] - r["observer.x2_hat[1]"])[late], lw=0.4)
    inset.set_title("t >= 1 s [rad/s]", fontsize=8)
    inset.tick_params(labelsize=7)
    return save(fig, out / "estimation_errors.png")


def plot_perturbation(s: Scenario, r: Records, out: Path) -> Path:
    t = r.time
    xi = true_perturbation(s, r)
    fig = Figure(figsize=(8, 5.5), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    # the identified trace first and the true one dashed on top: both stay visible
    axes[0].plot(t, r["observer.z_eq_filtered[1]"], label="identified (filtered z_eq)",
                 lw=1.4, color="C1")
    axes[0].plot(t, xi, label="true perturbation", **TRUE_STYLE)
    axes[0].set_ylabel("perturbation [rad/s²]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(_title(s, "perturbation", s.title), fontsize=10)
    error = r["observer.z_eq_filtered[1]"] - xi
    axes[1].plot(t, error, lw=0.4)
    axes[1].set_ylabel("identified - true [rad/s²]")
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylim(*_robust_limits(error[t >= s.transient]))  # the transient would hide it
    return save(fig, out / "perturbation.png")


def plot_parameters(s: Scenario, r: Records, out: Path) -> Path:
    t = r.time
    if s.kind == "mff":
        fig = Figure(figsize=(8, 4), layout="constrained")
        ax = fig.subplots()
        ax.plot(t, r["observer.theta_hat[1,2]"], label="MFF estimate", lw=1.0, color="C1")
        ax.plot(t, r["plant.d"], label="true d(t)", **TRUE_STYLE)
        ax.set_ylim(-0.5, 1.5)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("damping d [1/s]")
        ax.legend(fontsize=8)
        ax.set_title(_title(s, "parameters", s.title), fontsize=10)
        return save(fig, out / "parameters.png")
    fig = Figure(figsize=(8, 7), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    for k, ax in enumerate(axes):
        truth, nominal = s.c_true[k], s.c_nominal[k]
        ax.plot(t, r[f"observer.theta_hat[1,{k + 1}]"], lw=1.0, color="C1", label="LSM estimate")
        ax.axhline(truth, label="true", **TRUE_STYLE)
        ax.axhline(nominal, label="nominal (observer's model)", **NOMINAL_STYLE)
        span = max(0.5 * abs(truth), abs(nominal - truth) * 1.2, 0.1)
        ax.set_ylim(truth - span, truth + span)
        name, unit = COEFFICIENTS[k]
        ax.set_ylabel(f"{name} [{unit}]")
    axes[0].legend(fontsize=8, loc="lower right")
    axes[0].set_title(_title(s, "parameters", s.title), fontsize=10)
    axes[-1].set_xlabel("t [s]")
    return save(fig, out / "parameters.png")


def plot_scenario(s: Scenario, r: Records, out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    paths = [plot_errors(s, r, out)]
    paths.append(plot_perturbation(s, r, out) if s.kind == "perturbation"
                 else plot_parameters(s, r, out))
    return paths


def _moving_mean(x: np.ndarray, width: int) -> np.ndarray:
    if width <= 1 or len(x) < width:
        return x
    kernel = np.ones(width) / width
    return np.convolve(x, kernel, mode="same")


def _robust_limits(x: np.ndarray, include: list[float] | tuple = ()) -> tuple[float, float]:
    """The axis range of the central 99 % of x, widened to show the ``include`` values."""
    low, high = np.percentile(x, [0.5, 99.5])
    low, high = min([low, *include]), max([high, *include])
    pad = 0.1 * (high - low) or 0.1
    return float(low - pad), float(high + pad)


def plot_identification(t: np.ndarray, columns: Mapping[str, np.ndarray], out: Path,
                        nominal: Mapping[str, float] | None = None) -> Path:
    """Offline identification: velocity, perturbation and parameter estimates (+-2 sigma
    bands), with the nominal values the observer ran with as dotted lines."""
    nominal = nominal or {}
    fig = Figure(figsize=(8, 9), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True, height_ratios=[1, 1, 1.3, 1])
    axes[0].plot(t, columns["x2_hat"], lw=0.7)
    axes[0].set_ylabel("velocity x2_hat [rad/s]")
    # the injection is as noisy as the measurement differentiated twice: drawn faintly,
    # with its mean over 1 % of the record on top, and the axis fitted to that mean
    z = np.asarray(columns["z_eq_filtered"])
    smooth = _moving_mean(z, max(1, len(z) // 100))
    axes[1].plot(t, z, lw=0.4, color=_FAINT_C0, label="filtered z_eq")
    axes[1].plot(t, smooth, lw=1.0, color="C0", label="its moving mean (1 % of the record)")
    axes[1].set_ylim(*_robust_limits(smooth))
    axes[1].set_ylabel("perturbation [rad/s²]")
    axes[1].legend(fontsize=7, loc="upper right")
    shown: list[list[np.ndarray]] = [[], []]  # what axes 2 and 3 are fitted to
    marks: list[list[float]] = [[], []]  # nominal values they show in full
    for k in range(1, 6):
        key = f"theta_hat[1,{k}]"
        std = columns.get(f"theta_std[1,{k}]")
        if key not in columns or std is None or not np.any(std > 0):
            continue  # not identified
        name, unit = COEFFICIENTS[k - 1]
        line, = axes[2].plot(t, columns[key], lw=0.9, label=f"{name.split(' ')[0]} [{unit}]")
        axes[2].fill_between(t, columns[key] - 2 * std, columns[key] + 2 * std,
                             color=line.get_color(), alpha=0.2, lw=0)
        shown[0].append(np.asarray(columns[key]))
        if f"c_nominal[{k}]" in nominal:
            axes[2].axhline(nominal[f"c_nominal[{k}]"], color=line.get_color(), ls=":", lw=1.0)
            marks[0].append(nominal[f"c_nominal[{k}]"])
    axes[2].set_ylabel("coefficients\n(+-2 sigma; dotted: nominal)")
    if shown[0]:
        axes[2].legend(fontsize=7, ncol=3, loc="upper right")
    b = np.asarray(columns["b_hat"])
    line, = axes[3].plot(t, b, lw=0.9, color="C4", label="b_hat")
    if np.any(columns["b_std"] > 0):
        axes[3].fill_between(t, b - 2 * columns["b_std"], b + 2 * columns["b_std"],
                             color=line.get_color(), alpha=0.2, lw=0)
    shown[1].append(b)
    if "b" in nominal:
        axes[3].axhline(nominal["b"], label="nominal b", **NOMINAL_STYLE)
        marks[1].append(nominal["b"])
    axes[3].set_ylabel("input gain b [1/(kg m²)]")
    axes[3].legend(fontsize=7, loc="upper right")
    axes[3].set_xlabel("t since the first sample [s]")
    for ax, series, values in zip(axes[2:], shown, marks):  # the first 10 % left out
        if series:
            ax.set_ylim(*_robust_limits(np.concatenate([x[len(x) // 10:] for x in series]),
                                        values))
    axes[0].set_title("Offline identification of recorded data", fontsize=10)
    return save(fig, out / "identification.png")
