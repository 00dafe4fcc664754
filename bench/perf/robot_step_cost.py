"""Cost of one sample of the robot pipeline in C (core/robot_pipeline.c's rp_run: the
model-based observer with its forward dynamics, the regression, the LSM step over every
base parameter and the friction with its anchor re-solve every RRI_ANCHOR_INTERVAL
steps, the statistics' share), per example robot; with --fmu, of the RobotObserver
FMU's whole internal step.

    .venv/bin/python -m bench.perf.robot_step_cost [--steps 20000] [--runs 5] [--callgrind]
                                              [--against REVISION] [--identifier lsm|mff]
                                              [--fmu [--statistics-interval S]
                                               [--sample-period h] [--keep DIR]]

Runs bench/perf/robot_step.c as CMake built it (./build.sh fmus: the FMUs' flags) and prints the
wall time per step (the median of --runs runs) and, with --callgrind, the instructions.
--against builds a git revision's fmu/src too, with this checkout's CMake recipe and
driver (e.g. the commit before a change) and interleaves the two builds' runs, so
that both see the same load.  --identifier mff: MFF (R = 0.1, the FMU's default) instead
of LSM, in both (--fmu: the FMU's parameter identifier = 2).

--fmu runs bench/perf/robot_fmu_step.c built with the RobotObserver's sources (CMake's
robot_fmu_step target),
sets the parameters that `python -m harness robot-fmu-parameters URDF --step h`
writes (h = --sample-period, default 1e-4 s; every base parameter and the friction
identified, LSM; t_id moved to 0.02 s so that the warm-up is short) by value
reference, and feeds a multi-sine trajectory q with
its inverse-dynamics torques u.  After FMU_WARMUP doSteps of H = h (the identifier
then runs; the driver checks identifier_active), it measures the cost per internal
step of doSteps of H = h (a communication point per sample, as in a closed loop:
the observer with the forward dynamics, the regression, the identifier, the outputs,
and every statistics_interval = 0.1 s a solve with standard errors: the slowest doStep)
and of doSteps of H = 2000 h (the inputs held over each).  Instructions: callgrind
--toggle-collect=fmi2DoStep, the difference of runs with 1x and 2x the measured steps,
divided by the steps; at H = h also the distribution of the instructions per doStep
over 2000 doSteps (callgrind --dump-after=fmi2DoStep: one profile per call), with the
maximum: the doStep that a hard real-time loop must fit in its period.  With --against, the revision's FMU sources with this checkout's
driver (the model description's source list is this checkout's)."""
from __future__ import annotations

import argparse
import io
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Any

import numpy as np

from bench.reports.robot_trajectories import multisine
from harness.robot.base_parameters import base_parameters
from harness.robot.examples import example_urdf
from harness.robot.fmu import read_ssv
from harness.robot.native import core_defaults
from harness.robot.urdf import read_urdf

REPO = Path(__file__).resolve().parents[2]

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


FMU_DESCRIPTION = REPO / "fmu/src/models/RobotObserver/modelDescription.xml"
FMU_H = 1e-4        # [s] the sampling period: 10 kHz
FMU_T_ID = 0.02     # [s] the identifier starts here ...
FMU_WARMUP = 500    # ... before these doSteps of H = h end (0.05 s)


def build(binary: Path, revision: str | None, fmu: bool = False) -> None:
    """The step driver of the checkout's CMake build (./build.sh fmus), or the same
    driver built by this checkout's CMake recipe over a git revision's fmu/src."""
    target = "robot_fmu_step" if fmu else "robot_step"
    if revision is None:
        built = REPO / "build" / "cmake" / "bin" / target
        if not built.exists():
            raise SystemExit(f"{built} is missing: run ./build.sh fmus")
        shutil.copyfile(built, binary)
        binary.chmod(0o755)
        return
    root = binary.parent / f"src-{revision}"
    root.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(["git", "-C", str(REPO), "archive", revision, "fmu/src"],
                             capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(root, filter="data")
    # this checkout's recipe and drivers, so that revisions before them can be measured
    for name in ("CMakeLists.txt", "cmake", "bench/perf/step_driver.c", "bench/perf/robot_step.c",
                 "bench/perf/robot_fmu_step.c", "tools/abuse/closed_loop.c"):
        if (REPO / name).is_dir():
            shutil.copytree(REPO / name, root / name, dirs_exist_ok=True)
        else:
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(REPO / name, root / name)
    tree = binary.parent / f"build-{revision}"
    subprocess.run(["cmake", "-S", str(root), "-B", str(tree), "-G", "Ninja",
                    f"-DSTO_PYTHON={sys.executable}", "-DSTO_FMUS=OFF", "-DSTO_NATIVE=OFF",
                    "-DSTO_TESTS=OFF", "-DSTO_IMPORTER=OFF"], check=True, capture_output=True)
    subprocess.run(["cmake", "--build", str(tree), "--target", target], check=True)
    shutil.copyfile(tree / "bin" / target, binary)
    binary.chmod(0o755)


def _search(pattern: str, text: str, flags: int = 0) -> re.Match[str]:
    """re.search's match of `pattern` in `text`, which must match."""
    match = re.search(pattern, text, flags)
    if match is None:
        raise RuntimeError(f"no match of {pattern!r} in {text[-2000:]!r}")
    return match


def instructions(binary: Path, model: Path, tmp: str, steps: int = 2000,
                 identifier: str = "lsm") -> float:
    """Instructions per step: callgrind's count of 2 steps runs minus steps runs, / steps."""
    counts = []
    for count in (steps, 2 * steps):
        run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={tmp}/cg.out",
                              str(binary), str(model), str(count), identifier],
                             capture_output=True, text=True)
        counts.append(int(_search(r"Collected : (\d+)", run.stderr).group(1)))
    return (counts[1] - counts[0]) / steps


def fmu_files(name: str, tmp: Path, rows: int, statistics_interval: float | None = None,
              h: float = FMU_H, identifier: str = "lsm") -> tuple[Path, Path, int, int]:
    """(parameters, trajectory, n, p) of an example robot for robot_fmu_step.c, sampled
    every h [s]; the FMU's statistics_interval [s] unless given."""
    urdf, locked = example_urdf(name)
    ssv = tmp / f"{name}.ssv"
    subprocess.run([sys.executable, "-m", "harness", "robot-fmu-parameters", str(urdf),
                    "--out", str(ssv), "--step", repr(h), "--identifier", identifier,
                    *(f"--lock={joint}" for joint in locked)], cwd=REPO, check=True,
                   capture_output=True)
    values = {**read_ssv(ssv), "t_id": FMU_T_ID}
    if statistics_interval is not None:
        values["statistics_interval"] = statistics_interval
    root = ElementTree.parse(FMU_DESCRIPTION).getroot()
    kinds = {v.get("name"): (int(v.attrib["valueReference"]), child.tag[0])
             for v in root.iter("ScalarVariable") for child in v
             if child.tag in ("Real", "Integer", "Boolean")}
    n, p = int(values["n"]), int(values["base_count"])
    lines = [f"{root.get('guid')} {values['h']!r} {n}"]
    lines += [f"{kinds[key][1]} {kinds[key][0]} {value!r}" for key, value in values.items()]
    parameters = tmp / f"{name}.parameters"
    parameters.write_text("\n".join(lines) + "\n")
    # a moving robot: multi-sine positions and the nominal model's torques along them
    reference = multisine(n, seed=1)
    q, qd = (np.array(x) for x in zip(*(reference(k * h) for k in range(rows))))
    qdd = np.gradient(qd, h, axis=0)
    u = read_urdf(urdf, locked=locked).rigid_body().inverse_dynamics(q, qd, qdd)
    trajectory = tmp / f"{name}.trajectory"
    np.savetxt(trajectory, np.hstack([q, u]), header=str(rows), comments="")
    return parameters, trajectory, n, p


def fmu_run(binary: Path, files: tuple[Path, Path, int, int], steps: int, calls: int,
            callgrind: str | None = None) -> dict[str, Any]:
    """One run of robot_fmu_step over fmu_files' files, checked (status OK, identifying
    at the end, the FMU's n and base_count the robot's): {"ns": wall time per internal
    step, "slowest": of the slowest doStep [ns]}, with `callgrind` (the output file) and
    "instructions" collected in fmi2DoStep."""
    command = [str(binary), *map(str, files[:2]), str(FMU_WARMUP), str(steps), str(calls)]
    if callgrind:
        command = ["valgrind", "--tool=callgrind", "--toggle-collect=fmi2DoStep",
                   f"--callgrind-out-file={callgrind}", *command]
    run = subprocess.run(command, capture_output=True, text=True)
    line, _, watched = run.stdout.strip().partition("\n")
    expected = f"n={files[2]} base_count={files[3]}"
    if run.returncode != 0 or "status=0 identifier_active=1" not in line or \
            not line.endswith(expected):
        raise RuntimeError(f"{' '.join(command)}: failed or not identifying: {line!r} "
                           f"(expected ... {expected})\n{run.stderr[-2000:]}")
    result: dict[str, Any] = {
        key: float(_search(rf"{name}=([\d.]+)", line).group(1))
        for key, name in (("ns", "ns_per_step"), ("slowest", "slowest_call_ns"))}
    if callgrind:
        result["instructions"] = float(_search(r"Collected : (\d+)", run.stderr).group(1))
    started = _search(r"identifier_started=(-?\d+) statistics_published=([\d,]*)", watched)
    result["started"] = int(started.group(1))
    result["published"] = [int(x) for x in started.group(2).split(",") if x]
    return result


def per_call_instructions(binary: Path, files: tuple[Path, Path, int, int], calls: int,
                          directory: Path) -> np.ndarray:
    """Instructions of each of `calls` doSteps of H = h (after the warm-up): callgrind
    --dump-after=fmi2DoStep writes one profile per call, whose total is that call's count
    (collected in fmi2DoStep only)."""
    directory.mkdir(parents=True, exist_ok=True)
    out = directory / "cg.out"
    command = ["valgrind", "--tool=callgrind", "--toggle-collect=fmi2DoStep",
               "--dump-after=fmi2DoStep", f"--callgrind-out-file={out}", str(binary),
               *map(str, files[:2]), str(FMU_WARMUP), "1", str(calls)]
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode != 0 or "identifier_active=1" not in run.stdout:
        raise RuntimeError(f"{' '.join(command)}: failed or not identifying: {run.stdout!r}")
    dumps = sorted(directory.glob("cg.out.*"), key=lambda f: int(f.suffix[1:]))
    counts = np.array([int(_search(r"^totals: (\d+)", f.read_text(), re.M).group(1))
                       for f in dumps], dtype=float)
    shutil.rmtree(directory)
    if len(counts) != FMU_WARMUP + calls:
        raise RuntimeError(f"{len(counts)} profiles for {FMU_WARMUP + calls} doSteps")
    return counts[FMU_WARMUP:]


def statistics_lag(run: dict, interval: int) -> str:
    """Steps from each snapshot of the solve with statistics to its publication, at H = h:
    the first snapshot is taken in the identifier's first step, the next every `interval`
    steps while each job is done within the interval (the lag is then the publication's
    step after the identifier's start, modulo the interval; a publication that changes
    nothing, as before any equation entered the regression, is not seen)."""
    after = [c - run["started"] for c in run["published"]]
    return (f"statistics published {', '.join(map(str, after))} steps after the "
            f"identifier's start: {', '.join(str(a % interval) for a in after)} steps after "
            f"their snapshots if each job took less than the interval ({interval} steps)")


def distribution(counts: np.ndarray) -> str:
    """The per-doStep instructions: maximum, high percentiles, median, mean."""
    p50, p99, p999 = np.percentile(counts, [50, 99, 99.9])
    return (f"per doStep: max {counts.max():.0f} (call {int(np.argmax(counts))}), "
            f"99.9 % {p999:.0f}, 99 % {p99:.0f}, median {p50:.0f}, mean {counts.mean():.0f}")


def fmu_cost(args, binaries: dict[str, Path], tmp: Path) -> None:
    """The RobotObserver's internal step, per example robot, at H = h and in doSteps of
    H = 2000 h: wall time (median of the runs of --steps internal steps, the builds' runs
    interleaved), that of the slowest doStep (median over the runs) and callgrind's
    instructions."""
    count = 2000  # measured steps of a callgrind run, and of the doStep of H = count h
    for name in ("double_pendulum", "ur5", "panda"):
        files = fmu_files(name, tmp, FMU_WARMUP + max(args.steps, 2 * count),
                          args.statistics_interval, args.sample_period, args.identifier)
        n, p = files[2:]
        files_h = args.sample_period
        # H, (STEPS, CALLS) of a run measuring m times `count` steps, and of the timed runs
        # (--steps internal steps each)
        cases = (("h", lambda m: (1, m * count), (1, args.steps)),
                 (f"{count} h", lambda m: (count, m), (count, max(1, args.steps // count))))
        for H, measured, timed in cases:
            runs: dict[str, list[dict[str, Any]]] = {label: [] for label in binaries}
            for _ in range(args.runs):
                for label, binary in binaries.items():
                    runs[label].append(fmu_run(binary, files, *timed))
            for label, binary in binaries.items():
                ns, slowest = (np.median([r[key] for r in runs[label]]) / 1000
                               for key in ("ns", "slowest"))
                line = (f"{name} ({label}): n = {n}, p = {p}, H = {H}: {ns:.2f} us per step, "
                        f"slowest doStep {slowest:.0f} us")
                if H == "h":
                    interval = args.statistics_interval
                    interval = core_defaults().statistics_interval if interval is None else interval
                    line += f"; {statistics_lag(runs[label][0], round(interval / files_h))}"
                if args.callgrind and shutil.which("valgrind"):
                    case = f"{name}-{label}-H={H.replace(' ', '')}"
                    out = f"{args.keep or tmp}/callgrind.out.{case}"
                    counts = [fmu_run(binary, files, *measured(m), f"{out}-{m}x")
                              ["instructions"] for m in (1, 2)]
                    line += f", {(counts[1] - counts[0]) / count:.0f} instructions per step"
                    if H == "h":
                        per_call = per_call_instructions(binary, files, count,
                                                         tmp / f"dumps-{case}")
                        line += f"; {distribution(per_call)}"
                print(line, flush=True)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--runs", type=int, default=5, help="wall-time runs (the median is shown)")
    parser.add_argument("--callgrind", action="store_true")
    parser.add_argument("--fmu", action="store_true",
                        help="the RobotObserver FMU's whole internal step (bench/perf/robot_fmu_step.c)")
    parser.add_argument("--statistics-interval", type=float, metavar="S",
                        help="--fmu: the FMU's statistics_interval (default its 0.1 s)")
    parser.add_argument("--sample-period", type=float, default=FMU_H, metavar="h",
                        help="--fmu: the sampling period h [s] (default 1e-4)")
    parser.add_argument("--keep", type=Path, metavar="DIR",
                        help="--fmu: keep the callgrind outputs in DIR")
    parser.add_argument("--identifier", choices=("lsm", "mff"), default="lsm",
                        help="the identifier's kind (MFF: R = 0.1)")
    parser.add_argument("--against", metavar="REVISION",
                        help="also a git revision's core, its runs interleaved with this one's")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        binaries = {"now": Path(tmp) / "robot_step"}
        if args.against:
            binaries[args.against] = Path(tmp) / "robot_step_against"
        for label, binary in binaries.items():
            build(binary, None if label == "now" else label, args.fmu)
        if args.keep:
            args.keep.mkdir(parents=True, exist_ok=True)
        if args.fmu:
            fmu_cost(args, binaries, Path(tmp))
        for name in () if args.fmu else ("double_pendulum", "ur5", "panda"):
            model = Path(tmp) / f"{name}.txt"
            p = model_file(name, model)
            times: dict[str, list[float]] = {label: [] for label in binaries}
            for _ in range(args.runs):
                for label, binary in binaries.items():
                    times[label].append(float(subprocess.run(
                        [str(binary), str(model), str(args.steps), args.identifier],
                        capture_output=True, text=True, check=True).stdout))
            for label, binary in binaries.items():
                median = np.median(times[label]) / 1000
                line = f"{name} ({label}): p = {p}, {median:.2f} us per step"
                if args.callgrind and shutil.which("valgrind"):
                    line += (f", {instructions(binary, model, tmp, identifier=args.identifier):.0f}"
                             " instructions per step")
                print(line, flush=True)
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
