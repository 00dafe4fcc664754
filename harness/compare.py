"""Paper method vs the improved defaults, on every scenario, with and without noise.

``python -m harness compare --out DIR`` writes compare.csv, compare.md (a
side-by-side table) and one figure per scenario.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .json_files import write_json
from .master import Progress, Records
from .metrics import score
from .scenarios import SCENARIOS, Scenario, improved_overrides, run_scenario

NOISE_LEVELS = (0.0, 1e-5, 1e-4)  # std of the noise on theta [rad]

# The figures each kind of scenario is judged by.
HEADLINE = {
    "perturbation": ("rms_perturbation", "delay", "max_e2_after_1s"),
    "lsm": ("a1_rel_error_20s", "a2_rel_error_20s", "a3_rel_error_20s", "a1_rel_error_end",
            "a2_rel_error_end", "a3_rel_error_end", "max_e2_after_1s"),
    "mff": ("rms_damping", "damping_lag", "max_e2_after_1s"),
}


@dataclass
class Row:
    scenario: str
    noise: float
    metric: str
    paper: float
    improved: float


def compare_scenario(s: Scenario, fmu_dir: Path, noise: float, seed: int = 0,
                     quiet: bool | None = None
                     ) -> tuple[dict[str, float], dict[str, float], Records, Records]:
    """Runs the paper method and the improved one on the same noise sequence
    (``quiet``: see master.Progress)."""
    paper = run_scenario(s, fmu_dir, noise_std=noise, seed=seed,
                         progress=Progress(f"{s.name} paper, noise {noise:g}", quiet))
    better = run_scenario(s, fmu_dir, noise_std=noise, seed=seed,
                          observer_overrides=improved_overrides(s, noise),
                          progress=Progress(f"{s.name} improved, noise {noise:g}", quiet))
    return score(s, paper), score(s, better), paper, better


def plot_comparison(s: Scenario, noise: float, paper: Records, better: Records, out: Path) -> Path:
    """The velocity error of both methods, then what the scenario identifies: the
    perturbation or damping against the truth, or each coefficient's relative error
    in a panel of its own."""
    from matplotlib.figure import Figure

    from .plots import COEFFICIENTS, TRUE_STYLE, save

    t = paper.time
    methods = (("paper", paper, "C0"), ("improved", better, "C1"))
    panels = 4 if s.kind == "lsm" else 2
    fig = Figure(figsize=(8, 2.4 * panels + 0.6), layout="constrained")
    axes = fig.subplots(panels, 1, sharex=True)
    for label, r, color in methods:
        axes[0].semilogy(t, np.abs(r["plant.omega"] - r["observer.x2_hat[1]"]) + 1e-12, lw=0.5,
                         label=label, color=color)
    axes[0].set_ylabel("|x2 - x2_hat| [rad/s]")
    axes[0].legend(fontsize=8, loc="upper right")
    fig.suptitle(f"{s.title}\nnoise std {noise:g} rad: paper method vs improved defaults",
                 fontsize=10)
    if s.kind == "perturbation":
        from .metrics import true_perturbation

        for label, r, color in methods:
            axes[1].plot(t, r["observer.z_eq_filtered[1]"], lw=0.6, label=label, color=color)
        axes[1].plot(t, true_perturbation(s, paper), label="true", **TRUE_STYLE)
        axes[1].set_ylabel("perturbation [rad/s²]")
        axes[1].set_ylim(-1, 1)
        axes[1].legend(fontsize=7, ncol=3, loc="upper right")
    elif s.kind == "mff":
        for label, r, color in methods:
            axes[1].plot(t, r["observer.theta_hat[1,2]"], lw=0.6, label=label, color=color)
        axes[1].plot(t, paper["plant.d"], label="true d(t)", **TRUE_STYLE)
        axes[1].set_ylim(-0.5, 1.5)
        axes[1].set_ylabel("damping d [1/s]")
        axes[1].legend(fontsize=7, ncol=3, loc="upper right")
    else:
        for k, ax in enumerate(axes[1:]):
            truth = s.c_true[k]
            for label, r, color in methods:
                err = np.abs(r[f"observer.theta_hat[1,{k + 1}]"] - truth) / truth
                ax.semilogy(t, err + 1e-9, lw=0.7, label=label, color=color)
            ax.set_ylabel(f"{COEFFICIENTS[k][0].split(' ')[0]}: |relative error|")
            ax.set_ylim(1e-5, 10)
            ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("t [s]")
    return save(fig, out / f"compare_{s.name}_noise{noise:g}.png", dpi=100)


def run_comparison(fmu_dir: Path, out: Path, scenarios: list[str] | None = None,
                   noise_levels: tuple[float, ...] = NOISE_LEVELS,
                   quiet: bool | None = None) -> list[Row]:
    """Both methods on each scenario and noise level; writes compare.csv/.md/.json and a
    figure per scenario and noise level into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    rows: list[Row] = []
    for name in scenarios or list(SCENARIOS):
        s = SCENARIOS[name]
        for noise in noise_levels:
            paper, better, rp, rb = compare_scenario(s, fmu_dir, noise, quiet=quiet)
            plot_comparison(s, noise, rp, rb, out)
            for metric in HEADLINE[s.kind]:
                if metric in paper:
                    rows.append(Row(name, noise, metric, paper[metric], better[metric]))
    write_tables(rows, out)
    return rows


def write_tables(rows: list[Row], out: Path) -> None:
    with (out / "compare.csv").open("w") as f:
        f.write("scenario,noise_std,metric,paper,improved\n")
        for r in rows:
            f.write(f"{r.scenario},{r.noise!r},{r.metric},{r.paper!r},{r.improved!r}\n")
    # a metric never reached (a settling time) is inf: null in JSON
    write_json(out / "compare.json", [r.__dict__ for r in rows], indent=1, warn=False)
    (out / "compare.md").write_text(markdown_table(rows) + "\n")


def markdown_table(rows: list[Row]) -> str:
    lines = ["| scenario | noise std [rad] | metric | paper | improved |",
             "|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r.scenario} | {r.noise:g} | {r.metric} | {r.paper:.3g} | "
                     f"{r.improved:.3g} |")
    return "\n".join(lines)
