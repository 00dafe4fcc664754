"""Instructions per internal step of the model file's FMU (ModelObserver) for n = 1, 2, 4.

    .venv/bin/python -m bench.perf.model_step_cost [--steps 2000]

For each model file (examples/pendulum: n = 1; examples/two_mass: n = 2; a chain of
four masses written here: n = 4) writes its FMU with `sto-harness fmu` (its defaults:
scheme 3, LSM, h = 1 ms), then counts with callgrind the instructions executed inside
the doStep (`--toggle-collect=instance_do_step`, under fmi2DoStep) while this module
drives it (`--drive`): STEPS and 2 STEPS internal steps, the count of the second run minus the first's over
STEPS (the steady state after STEPS h), in doSteps of H = h (a communication point per
step, as a closed loop calls it) and of H = 100 h.  Inputs: each coordinate
0.1 sin((i + 1) t) + 0.02 t, each input sin(2 t), held over each doStep.  The counts
repeat exactly; the Python driver's own work is not counted.
"""
from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

CHAIN4 = """[model]
coordinates = ["x1", "x2", "x3", "x4"]
inputs = ["F"]
equations = [
    "m1*der(x1,2) + c1*der(x1) + k*(x1 - x2) = F",
    "m2*der(x2,2) + c2*der(x2) + k*(2*x2 - x1 - x3) = 0",
    "m3*der(x3,2) + c3*der(x3) + k*(2*x3 - x2 - x4) = 0",
    "m4*der(x4,2) + c4*der(x4) + k*(x4 - x3) = 0",
]

[parameters]
m1 = { nominal = 2.0 }
m2 = { nominal = 1.0 }
m3 = { nominal = 1.0 }
m4 = { nominal = 1.5 }
c1 = { nominal = 0.5 }
c2 = { nominal = 0.5 }
c3 = { nominal = 0.5 }
c4 = { nominal = 0.5 }
k  = { nominal = 400 }
"""


def drive(fmu: str, steps: int, per_call: int) -> None:
    """Runs `steps` internal steps in doSteps of per_call steps (under callgrind)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(fmu)
    h = float(next(v.start for v in md.modelVariables if v.name == "observer.h"))
    inputs = [v for v in md.modelVariables
              if v.causality == "input" and v.type == "Real"]
    unzipped = extract(fmu)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="cost")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    outputs = {v.name for v in md.modelVariables if v.causality == "output"}
    coordinates = [v for v in inputs if f"der({v.name})" in outputs]
    vrs = [v.valueReference for v in inputs]
    H = per_call * h
    for c in range(steps // per_call):
        t = c * H
        values = [0.1 * math.sin((i + 1) * t) + 0.02 * t if v in coordinates else math.sin(2 * t)
                  for i, v in enumerate(inputs)]
        slave.setReal(vrs, values)
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=H)
    slave.terminate()
    slave.freeInstance()


def count(fmu: Path, steps: int, per_call: int, out: Path) -> int:
    # the FMU's exported fmi2DoStep has no name callgrind can match: the instance
    # core's instance_do_step under it is the doStep but for the API's call
    subprocess.run(["valgrind", "--tool=callgrind", "--toggle-collect=instance_do_step",
                    f"--callgrind-out-file={out}", sys.executable, "-m", "bench.perf.model_step_cost",
                    "--drive", str(fmu), "--steps", str(steps), "--per-call", str(per_call)],
                   cwd=REPO, check=True, capture_output=True)
    for line in out.read_text().splitlines():
        if line.startswith(("summary:", "totals:")) and int(line.split()[1]) > 0:
            return int(line.split()[1])
    raise RuntimeError(f"no instructions counted in instance_do_step: {out}")


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--drive", help=argparse.SUPPRESS)
    parser.add_argument("--per-call", type=int, default=1, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.drive:
        drive(args.drive, args.steps, args.per_call)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        chain = work / "chain4.toml"
        chain.write_text(CHAIN4)
        models = [(1, REPO / "examples/pendulum/pendulum.toml"),
                  (2, REPO / "examples/two_mass/two_mass.toml"), (4, chain)]
        print(f"{'n':>2} {'model':<14} {'H = h':>10} {'H = 100 h':>10}   (instructions per "
              f"internal step, steps {args.steps}..{2 * args.steps})")
        for n, model in models:
            out = work / model.stem
            subprocess.run([sys.executable, "-m", "harness", "fmu", "--model", str(model),
                            "--out", str(out), "-q"], cwd=REPO, check=True, capture_output=True,
                           env={**os.environ, "STO_FMU_DIR": str(REPO / "build" / "fmus")})
            fmu = next(out.glob("*.fmu"))
            row = []
            for per_call in (1, 100):
                first = count(fmu, args.steps, per_call, work / f"{model.stem}-{per_call}-1")
                second = count(fmu, 2 * args.steps, per_call, work / f"{model.stem}-{per_call}-2")
                row.append((second - first) / args.steps)
            print(f"{n:>2} {model.stem:<14} {row[0]:>10.0f} {row[1]:>10.0f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
