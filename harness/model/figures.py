"""Figures of the identify and validate commands (matplotlib's Figure, no pyplot state)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from .estimates import Estimates
from .model import Model

#: A log longer than twice this many samples is drawn as this many stretches' smallest
#: and largest values (the envelope a dense line fills at the figure's resolution, a
#: tenth of the drawing's time).
BINS = 2000


def _unit(model: Model, name: str, per_second: int = 0) -> str:
    unit = model.units.get(name, "")
    if per_second:
        unit = f"{unit or '1'}/s" if per_second == 1 else f"{unit or '1'}/s²"
    return f" [{unit}]" if unit else ""


def _save(figure: Figure, path: Path) -> Path:
    from matplotlib import rc_context

    with rc_context({"agg.path.chunksize": 5000}):
        figure.savefig(path, dpi=100, bbox_inches="tight")
    return path


def _envelope(t: np.ndarray, low: np.ndarray, high: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, smallest of low, largest of high) per stretch of a long log; the samples
    themselves for a short one."""
    if len(t) <= 2 * BINS:
        return t, low, high
    edges = np.linspace(0, len(t), BINS + 1).astype(int)[:-1]
    return (t[edges], np.minimum.reduceat(low, edges), np.maximum.reduceat(high, edges))


def plot_estimates(t: np.ndarray, estimates: Estimates, model: Model, path: Path) -> Path:
    """Each coordinate's position and causal velocity with +-2 sigma bands."""
    n = len(model.coordinates)
    figure = Figure(figsize=(9, 2.6 * n + 0.6), layout="constrained")
    axes = np.atleast_2d(figure.subplots(n, 2, sharex=True, squeeze=False))
    for i, c in enumerate(model.coordinates):
        for j, (value, std, label) in enumerate((
                (estimates.position, estimates.position_std, f"{c}{_unit(model, c)}"),
                (estimates.velocity, estimates.velocity_std,
                 f"der({c}){_unit(model, c, 1)}"))):
            ax = axes[i, j]
            x, sigma = value[:, i], std[:, i]
            times, low, high = _envelope(t, x - 2 * sigma, x + 2 * sigma)
            ax.fill_between(times, low, high, color="C0", alpha=0.3, lw=0, label="±2σ")
            times, smallest, largest = _envelope(t, x, x)
            if len(times) == len(t):
                ax.plot(t, x, lw=0.7, color="C0", label="estimate")
            else:  # a long log: the estimate's own envelope
                ax.fill_between(times, smallest, largest, color="C0", lw=0.7,
                                label="estimate")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[i, 1].legend(loc="upper right", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    figure.suptitle("identify: positions and causal velocities (observer), ±2σ bands",
                    fontsize=10)
    return _save(figure, path)


def plot_validation(t: np.ndarray, r: np.ndarray, predicted: np.ndarray, model: Model,
                    path: Path, title: str) -> Path:
    """Per equation: the known side measured, as the model reconstructs it, and the error."""
    n = r.shape[1]
    figure = Figure(figsize=(9, 2.6 * n + 0.6), layout="constrained")
    axes = figure.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for i, ax in enumerate(axes):
        ax.plot(t, r[:, i], lw=0.9, color="k", label="measured (known side)")
        ax.plot(t, predicted[:, i], lw=0.8, ls="--", color="C3", label="model")
        ax.plot(t, predicted[:, i] - r[:, i], lw=0.6, color="C0", label="error")
        ax.set_ylabel(f"equation {i + 1} (SI)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t [s]")
    figure.suptitle(title, fontsize=10)
    return _save(figure, path)
