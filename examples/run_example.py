"""An example end to end: simulate its two logs, identify, validate, write its FMU, feed
the FMU the estimation log (fmpy) and plot how its estimates converge.

    python examples/run_example.py pendulum|two_mass|oscillator --out DIR [--figures FOLDER]

Runs the same commands as the example's README, in DIR; with --figures, copies the
figures the README shows into FOLDER (validation.png, fmu_convergence.png).
"""
from __future__ import annotations

import argparse
import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parent


def command(*args: str) -> None:
    print("$ sto-harness", " ".join(args))
    subprocess.run([sys.executable, "-m", "harness", *args], check=True)


def feed_fmu(fmu: Path, model_file: Path, log: Path) -> tuple[dict, list[str]]:
    """The FMU fed the log at its rate: its outputs at every sample."""
    import fmpy
    import pandas as pd

    from harness.model import read_model

    model = read_model(model_file)
    data = pd.read_csv(log)
    names = [*model.coordinates, *model.inputs]
    time = data[model.column("t")].to_numpy()
    signals = np.zeros(len(data), dtype=[("time", float)] + [(n, float) for n in names])
    signals["time"] = time - time[0]
    for name in names:
        signals[name] = data[model.column(name)]
    step = float(signals["time"][1])
    unknowns = [p.name for p in model.parameters]
    result = fmpy.simulate_fmu(str(fmu), input=signals, step_size=step, output_interval=step,
                               stop_time=float(signals["time"][-1]),
                               start_values={"observer.h": step},
                               output=unknowns + [f"{n}_std" for n in unknowns])
    return {n: np.asarray(result[n]) for n in result.dtype.names}, unknowns


def plot_convergence(outputs: dict, unknowns: list[str], truth: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(unknowns), 1, figsize=(8, 1.6 * len(unknowns)), sharex=True)
    t = outputs["time"]
    for ax, name in zip(np.atleast_1d(axes), unknowns):
        value, std = outputs[name], outputs[f"{name}_std"]
        ax.plot(t, value, color="C0", lw=1.2, label="FMU estimate")
        ax.fill_between(t, value - 2 * std, value + 2 * std, color="C0", alpha=0.2,
                        label="+-2 sigma")
        ax.axhline(truth[name], color="k", lw=0.8, ls="--", label="simulated truth")
        final = value[-1]
        span = max(abs(final) * 0.2, 4 * std[-1], 1e-9)
        ax.set_ylim(final - span, final + span)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[0].legend(loc="upper right", fontsize=7)
    np.atleast_1d(axes)[-1].set_xlabel("t [s]")
    fig.suptitle("The FMU's estimates while the log streams through it", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("example", choices=("pendulum", "two_mass", "oscillator"))
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--figures", type=Path, default=None)
    args = parser.parse_args()
    folder, out = EXAMPLES / args.example, args.out
    spec = importlib.util.spec_from_file_location("simulate", folder / "simulate.py")
    assert spec is not None and spec.loader is not None
    simulate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(simulate)
    subprocess.run([sys.executable, str(folder / "simulate.py"), "--out", str(out)], check=True)
    model = folder / f"{args.example}.toml"
    log, validation = out / f"{args.example}.csv", out / f"{args.example}_validation.csv"
    command("identify", str(log), "--model", str(model), "--out", str(out / "identified"))
    command("validate", str(validation), "--model", str(out / "identified" / "identified.toml"),
            "--out", str(out / "validation"))
    command("fmu", "--model", str(model), "--out", str(out / "fmu"))
    outputs, unknowns = feed_fmu(out / "fmu" / f"{args.example}.fmu", model, log)
    plot_convergence(outputs, unknowns, simulate.TRUTH, out / "fmu_convergence.png")
    print("the FMU's final estimates (simulated truth):")
    for name in unknowns:
        print(f"  {name} = {outputs[name][-1]:.6g} +- {outputs[f'{name}_std'][-1]:.2g} "
              f"({simulate.TRUTH[name]})")
    if args.figures:
        args.figures.mkdir(parents=True, exist_ok=True)
        shutil.copy(out / "validation" / "validation.png", args.figures / "validation.png")
        shutil.copy(out / "fmu_convergence.png", args.figures / "fmu_convergence.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
