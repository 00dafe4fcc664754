#!/usr/bin/env python3
"""Write the plan for tools/dist/run_reference.c from an FMU: its default experiment,
the value references of its Real (FMI 2) or Float64 (FMI 3) outputs, and the reference
result it ships (FMI-LS-REF), as plain text a small C program can read.

    python -m tools.dist.plan FMU PLAN [--tolerance T]

Integer and Boolean outputs are left out (run_reference reads Float64 only); the
plan says how many outputs it compares.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tools.importers import make_reference as mr

REAL_TYPES = ("Real", "Float64")


def write_plan(fmu: Path, plan: Path, tolerance: float) -> str:
    """Writes the plan; returns a one-line summary."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    desc = mr.read_description(fmu)
    reference = mr.read_reference(fmu)
    exp = desc.experiment
    variables = {v.name: v for v in md.modelVariables}
    outputs = [(name, shape) for name, type_, shape in desc.outputs if type_ in REAL_TYPES]
    labels = [label for label, type_, name, _ in desc.columns if type_ in REAL_TYPES]
    missing = [label for label in labels if label not in reference.columns]
    if missing:
        raise SystemExit(f"{fmu}: the reference lacks {missing[:3]}")
    lines = [f"fmi {md.fmiVersion[0]}", f"token {md.guid}",
             f"experiment {exp.start!r} {exp.stop!r} {exp.step!r} {exp.decimation} {tolerance!r}",
             f"outputs {len(outputs)}"]
    for name, shape in outputs:
        count = 1
        for n in shape:
            count *= n
        lines.append(f"{variables[name].valueReference} {count}")
    lines.append(f"rows {len(reference.times)} {1 + len(labels)}")
    for i, t in enumerate(reference.times):
        lines.append(" ".join([repr(float(t))] + [repr(float(reference.columns[label][i]))
                                                  for label in labels]))
    plan.write_text("\n".join(lines) + "\n")
    return (f"{fmu.name}: FMI {md.fmiVersion}, {len(labels)} Float64 output values of "
            f"{len(desc.columns)} compared over {len(reference.times)} rows")


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("fmu", type=Path)
    parser.add_argument("plan", type=Path)
    parser.add_argument("--tolerance", type=float, default=1e-9,
                        help="largest |value - reference| / max(1, max |reference column|)")
    args = parser.parse_args(argv)
    print(write_plan(args.fmu, args.plan, args.tolerance))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
