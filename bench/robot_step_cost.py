"""Cost of one internal step of the robot identifier in C (regressor, nominal torques
Y pi, LSM step over every base parameter and the friction, with its anchor re-solve
every RRI_ANCHOR_INTERVAL steps), per example robot.

    .venv/bin/python bench/robot_step_cost.py [--steps 20000] [--runs 5] [--callgrind]
                                              [--against REVISION]

Compiles bench/robot_step.c with the core at -O2 (the FMU's flags) and prints the
wall time per step (the median of --runs runs) and, with --callgrind, the instructions.
--against builds the same files of a git revision too (e.g. the commit before a change)
and interleaves the two builds' runs, so that both see the same load."""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from harness.robot.base_parameters import base_parameters  # noqa: E402
from harness.robot.examples import example_urdf  # noqa: E402
from harness.robot.urdf import read_urdf  # noqa: E402

CFLAGS = ["-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2", "-D_POSIX_C_SOURCE=199309L"]


def model_file(name: str, path: Path) -> int:
    urdf, locked = example_urdf(name)
    robot = read_urdf(urdf, locked=locked)
    a = robot.arrays()
    base = base_parameters(robot.rigid_body(), a["types"], robot.joint_names)
    lines = [str(robot.n)]
    for i in range(robot.n):
        values = [a["types"][i], *a["axis"][i], *a["xyz"][i], *a["rpy"][i], *a["link"][i],
                  *a["friction"][i]]
        lines.append(" ".join(f"{v!r}" if isinstance(v, float) else str(v) for v in map(
            lambda v: float(v) if not isinstance(v, (int, np.integer)) else int(v), values)))
    lines.append(" ".join(map(str, [base.count, *base.base])))
    path.write_text("\n".join(lines) + "\n")
    return base.count


SOURCES = ("bench/robot_step.c", "fmu/src/core/rigid_body.c", "fmu/src/core/regressor_identifier.c")
HEADERS = ("fmu/src/core/rigid_body.h", "fmu/src/core/regressor_identifier.h",
           "fmu/src/core/cholesky.h")  # cholesky.h: since 1e4f058


def build(binary: Path, revision: str | None) -> None:
    """The step driver with the core of the checkout, or of a git revision."""
    root = REPO
    if revision is not None:
        root = binary.parent / f"src-{revision}"
        for name in SOURCES + HEADERS:
            shown = subprocess.run(["git", "-C", str(REPO), "show", f"{revision}:{name}"],
                                   capture_output=True)
            if shown.returncode != 0 and name in HEADERS:
                continue  # a header the revision did not have yet
            shown.check_returncode()
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            (root / name).write_bytes(shown.stdout)
    subprocess.run(["gcc", *CFLAGS, f"-I{root / 'fmu/src/core'}", "-o", str(binary),
                    *(str(root / name) for name in SOURCES), "-lm"], check=True)


def instructions(binary: Path, model: Path, tmp: str, steps: int = 2000) -> float:
    """Instructions per step: callgrind's count of 2 steps runs minus steps runs, / steps."""
    counts = []
    for count in (steps, 2 * steps):
        run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={tmp}/cg.out",
                              str(binary), str(model), str(count)], capture_output=True, text=True)
        counts.append(int(re.search(r"Collected : (\d+)", run.stderr).group(1)))
    return (counts[1] - counts[0]) / steps


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--runs", type=int, default=5, help="wall-time runs (the median is shown)")
    parser.add_argument("--callgrind", action="store_true")
    parser.add_argument("--against", metavar="REVISION",
                        help="also a git revision's core, its runs interleaved with this one's")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        binaries = {"now": Path(tmp) / "robot_step"}
        if args.against:
            binaries[args.against] = Path(tmp) / "robot_step_against"
        for label, binary in binaries.items():
            build(binary, None if label == "now" else label)
        for name in ("double_pendulum", "ur5", "panda"):
            model = Path(tmp) / f"{name}.txt"
            p = model_file(name, model)
            times = {label: [] for label in binaries}
            for _ in range(args.runs):
                for label, binary in binaries.items():
                    times[label].append(float(subprocess.run(
                        [str(binary), str(model), str(args.steps)], capture_output=True,
                        text=True, check=True).stdout))
            for label, binary in binaries.items():
                median = np.median(times[label]) / 1000
                line = f"{name} ({label}): p = {p}, {median:.2f} us per step"
                if args.callgrind and shutil.which("valgrind"):
                    line += f", {instructions(binary, model, tmp):.0f} instructions per step"
                print(line, flush=True)
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
