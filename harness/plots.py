"""Figures of a scenario run, matching the paper's figures 1-6."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: works on machines without a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .master import Records  # noqa: E402
from .metrics import true_perturbation  # noqa: E402
from .scenarios import Scenario  # noqa: E402

PAPER_FIGURE = {("6.1-sine", "perturbation"): 1, ("6.1-square", "perturbation"): 2,
                ("6.2", "errors"): 3, ("6.2", "parameters"): 4, ("6.3", "errors"): 5,
                ("6.3", "parameters"): 6}


def _title(s: Scenario, what: str, text: str) -> str:
    figure = PAPER_FIGURE.get((s.name, what))
    return f"{text} (cf. paper figure {figure})" if figure else text


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_errors(s: Scenario, r: Records, out: Path) -> Path:
    t = r.time
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    axes[0].plot(t, r["plant.theta"] - r["observer.x1_hat[1]"], lw=0.6)
    axes[0].set_ylabel("x1 - x1_hat [rad]")
    axes[1].plot(t, r["plant.omega"] - r["observer.x2_hat[1]"], lw=0.6)
    axes[1].set_ylabel("x2 - x2_hat [rad/s]")
    axes[1].set_xlabel("t [s]")
    axes[0].set_title(_title(s, "errors", f"{s.title}: estimation errors"))
    inset = axes[1].inset_axes([0.55, 0.55, 0.42, 0.4])
    late = t >= 1.0
    inset.plot(t[late], (r["plant.omega"] - r["observer.x2_hat[1]"])[late], lw=0.4)
    inset.set_title("t >= 1 s", fontsize=8)
    inset.tick_params(labelsize=7)
    return _save(fig, out / "estimation_errors.png")


def plot_perturbation(s: Scenario, r: Records, out: Path) -> Path:
    t = r.time
    xi = true_perturbation(s, r)
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    axes[0].plot(t, xi, label="true perturbation", lw=1.2)
    axes[0].plot(t, r["observer.z_eq_filtered[1]"], label="identified (filtered z_eq)", lw=0.8)
    axes[0].set_ylabel("[rad/s2]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(_title(s, "perturbation", f"{s.title}"))
    axes[1].plot(t, r["observer.z_eq_filtered[1]"] - xi, lw=0.6)
    axes[1].set_ylabel("error [rad/s2]")
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylim(-0.3, 0.3)
    return _save(fig, out / "perturbation.png")


def plot_parameters(s: Scenario, r: Records, out: Path) -> Path:
    t = r.time
    if s.kind == "mff":
        fig, ax = plt.subplots(figsize=(8, 4))
        ax.plot(t, r["plant.d"], label="true d(t)", lw=1.2)
        ax.plot(t, r["observer.theta_hat[1,2]"], label="MFF estimate", lw=0.8)
        ax.set_ylim(-0.5, 1.5)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("damping [1/s]")
        ax.legend(fontsize=8)
        ax.set_title(_title(s, "parameters", s.title))
        return _save(fig, out / "parameters.png")
    names = ["a1 = MgL/(2J)", "a2 = Vs/J", "a3 = Ps/J"]
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for k, ax in enumerate(axes):
        truth = s.c_true[k]
        ax.plot(t, r[f"observer.theta_hat[1,{k + 1}]"], lw=0.8, label="LSM estimate")
        ax.axhline(truth, color="k", ls="--", lw=0.8, label="true")
        ax.set_ylim(truth - max(0.5 * abs(truth), 0.1), truth + max(0.5 * abs(truth), 0.1))
        ax.set_ylabel(names[k])
    axes[0].legend(fontsize=8)
    axes[0].set_title(_title(s, "parameters", s.title))
    axes[-1].set_xlabel("t [s]")
    return _save(fig, out / "parameters.png")


def plot_scenario(s: Scenario, r: Records, out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    paths = [plot_errors(s, r, out)]
    paths.append(plot_perturbation(s, r, out) if s.kind == "perturbation"
                 else plot_parameters(s, r, out))
    return paths


def plot_identification(t: np.ndarray, columns: dict[str, np.ndarray], out: Path) -> Path:
    """Offline identification: velocity, perturbation and parameter estimates."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    axes[0].plot(t, columns["x2_hat"], lw=0.7)
    axes[0].set_ylabel("x2_hat [rad/s]")
    axes[1].plot(t, columns["z_eq_filtered"], lw=0.7)
    axes[1].set_ylabel("perturbation [rad/s2]")
    for k in range(1, 6):
        key = f"theta_hat[1,{k}]"
        if key in columns:
            line, = axes[2].plot(t, columns[key], lw=0.8, label=f"c_{k}")
            std = columns.get(f"theta_std[1,{k}]")
            if std is not None and np.any(std > 0):  # +-2 sigma band
                axes[2].fill_between(t, columns[key] - 2 * std, columns[key] + 2 * std,
                                     color=line.get_color(), alpha=0.2, lw=0)
    if "b_hat" in columns:
        line, = axes[2].plot(t, columns["b_hat"], lw=0.8, label="b")
        if np.any(columns["b_std"] > 0):
            axes[2].fill_between(t, columns["b_hat"] - 2 * columns["b_std"],
                                 columns["b_hat"] + 2 * columns["b_std"],
                                 color=line.get_color(), alpha=0.2, lw=0)
    axes[2].set_ylabel("coefficients (+-2 sigma)")
    axes[2].legend(fontsize=8, ncol=6)
    axes[2].set_xlabel("t [s]")
    axes[0].set_title("Offline identification of recorded data")
    return _save(fig, out / "identification.png")
