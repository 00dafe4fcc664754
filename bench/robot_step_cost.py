"""Cost of one internal step of the robot identifier in C (regressor, nominal torques
Y pi, LSM step over every base parameter and the friction, with its anchor re-solve
every RRI_ANCHOR_INTERVAL steps), per example robot.

    .venv/bin/python bench/robot_step_cost.py [--steps 20000] [--callgrind]

Compiles bench/robot_step.c with the core at -O2 (the FMU's flags) and prints the
wall time per step (the median of 5 runs) and, with --callgrind, the instructions."""
from __future__ import annotations

import argparse
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


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--callgrind", action="store_true")
    args = parser.parse_args()
    core = REPO / "fmu" / "src" / "core"
    with tempfile.TemporaryDirectory() as tmp:
        binary = Path(tmp) / "robot_step"
        subprocess.run(["gcc", *CFLAGS, f"-I{core}", "-o", str(binary),
                        str(REPO / "bench" / "robot_step.c"), str(core / "rigid_body.c"),
                        str(core / "regressor_identifier.c"), "-lm"], check=True)
        for name in ("double_pendulum", "ur5", "panda"):
            model = Path(tmp) / f"{name}.txt"
            p = model_file(name, model)
            times = sorted(float(subprocess.run([str(binary), str(model), str(args.steps)],
                                                capture_output=True, text=True,
                                                check=True).stdout) for _ in range(5))
            line = f"{name}: p = {p}, {times[2] / 1000:.2f} us per step"
            if args.callgrind and shutil.which("valgrind"):
                steps = 2000
                counts = []
                for count in (steps, 2 * steps):
                    run = subprocess.run(["valgrind", "--tool=callgrind",
                                          f"--callgrind-out-file={tmp}/cg.out", str(binary),
                                          str(model), str(count)], capture_output=True, text=True)
                    counts.append(int(re.search(r"Collected : (\d+)", run.stderr).group(1)))
                line += f", {(counts[1] - counts[0]) / steps:.0f} instructions per step"
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
