"""identify --robot on a long log: wall time and peak memory of
``sto-harness identify LOG --robot URDF``.

    python -m bench.perf.identify_robot_log [--samples 1000000] [--velocity sg|observer]
                                       [--imports-only]

Writes a log of N samples at 1 kHz of the two-link arm (example-robot-data's double
pendulum with a 0.3 kg tip payload and joint friction) along the robot tests'
analytic multi-sine (tests/harness/robot/robot_helpers.py: exact positions, torques by
the C core's inverse dynamics), its positions rounded to 17-bit encoders, into a
temporary folder; then runs the command line on it in a child process and reports the
child's wall time and peak resident memory (its own rusage from wait4: ru_maxrss).
--imports-only measures children that only import what the command imports (before
it reads the log; and with the reader's pandas and the plot's matplotlib) for the
split between the imports and the work.  The log is written by another child, and this process imports
neither numpy nor the harness: Linux carries the peak memory of the process that
starts a program over into the program's ru_maxrss, so a large parent would be counted.
The target: 10^6 samples of 2 joints within 300 MB.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
# what the command imports before it reads the log, and with what the reader (pandas)
# and the plot (matplotlib) import on the way
IMPORTS = {
    "the command": "import harness.cli, harness.robot.cli, harness.robot.pipeline, harness.robot.results; "
                   "harness.cli.build_parser()",
    "all it imports": "import harness.cli, harness.robot.cli, harness.robot.pipeline, harness.robot.results, pandas, "
                      "matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot; "
                      "harness.cli.build_parser()",
}


def write_log(path: Path, samples: int, h: float = 1e-3, bits: int = 17,
              chunk: int = 100_000) -> None:
    """The arm's log (t, q1, q2, u1, u2) in chunks: the multi-sine and friction of the
    robot tests, torques by inverse dynamics."""
    import importlib.util

    import numpy as np
    import pyarrow as pa
    import pyarrow.csv as pacsv

    # the robot tests' helpers, loaded from their file (tests/ is not a package)
    spec = importlib.util.spec_from_file_location(
        "robot_helpers", REPO / "tests" / "harness" / "robot" / "robot_helpers.py")
    assert spec is not None and spec.loader is not None
    helpers = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(helpers)
    FRICTION, multisine_log, payload_link = (helpers.FRICTION, helpers.multisine_log,
                                             helpers.payload_link)

    from harness.robot.examples import example_urdf
    from harness.robot.urdf import read_urdf

    robot = read_urdf(example_urdf("double_pendulum")[0])
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    resolution = 2 * np.pi / 2 ** bits
    names = ["t", "q1", "q2", "u1", "u2"]
    with pacsv.CSVWriter(str(path), pa.schema([(name, pa.float64()) for name in names])) as out:
        for start in range(0, samples, chunk):
            count = min(chunk, samples - start)
            t, q, _, _, tau = multisine_log(truth, count * h, h, start=start * h)
            t, q, tau = t[:count], q[:count], tau[:count]  # arange's rounding: no extra
            q = np.round(q / resolution) * resolution
            out.write_table(pa.table(dict(zip(names, [t, *q.T, *tau.T]))))


def measure(command: list[str], folder: Path) -> tuple[float, float, int, str]:
    """(wall s, peak resident MB, exit status, stderr) of a child running `command`."""
    errors = (folder / "stderr.txt").open("w+")
    start = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=errors, cwd=REPO)
    _, status, usage = os.wait4(child.pid, 0)  # this child's own rusage
    wall = time.perf_counter() - start
    child.returncode = os.waitstatus_to_exitcode(status)  # reaped here
    errors.seek(0)
    return wall, usage.ru_maxrss / 1024, child.returncode, errors.read()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--velocity", choices=["sg", "observer"], default="sg")
    parser.add_argument("--imports-only", action="store_true")
    parser.add_argument("--write-log", type=Path, help=argparse.SUPPRESS)  # the writing child
    args = parser.parse_args()
    if args.write_log:
        write_log(args.write_log, args.samples)
        return 0
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        if args.imports_only:
            for what, code in IMPORTS.items():
                wall, peak, status, errors = measure([sys.executable, "-c", code], folder)
                if status:
                    print(errors, file=sys.stderr)
                    return 1
                print(f"imports, {what} ({code}): {wall:.1f} s wall, peak resident memory "
                      f"{peak:.0f} MB")
            return 0
        log = folder / "log.csv"
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "bench.perf.identify_robot_log",
                        "--samples", str(args.samples),
                        "--write-log", str(log)], check=True, cwd=REPO)
        print(f"log: {args.samples} samples of 2 joints, {log.stat().st_size / 1e6:.0f} MB "
              f"(written in {time.perf_counter() - start:.1f} s)")
        from_urdf = ("import sys; from harness.robot.examples import example_urdf; "
                     "print(example_urdf('double_pendulum')[0])")
        urdf = subprocess.run([sys.executable, "-c", from_urdf], check=True, cwd=REPO,
                              capture_output=True, text=True).stdout.strip()
        command = [sys.executable, "-m", "harness", "identify", str(log), "--robot", urdf,
                   "--unknown", "payload", "--velocity", args.velocity,
                   "--out", str(folder / "out"), "--quiet"]
        wall, peak, status, errors = measure(command, folder)
        if status not in (0, 1):
            print(errors, file=sys.stderr)
            return 1
        print(f"identify --robot --velocity {args.velocity}: {wall:.1f} s wall, peak "
              f"resident memory {peak:.0f} MB, exit status {status}")
        print(f"{args.samples / wall / 1e6:.2f} million samples per second")
    return 0


if __name__ == "__main__":
    sys.exit(main())
