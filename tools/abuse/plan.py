"""Writes the plan of a closed-loop scenario for tools/abuse/closed_loop.c.

    python -m tools.abuse.plan SCENARIO LIBRARY_ROOT FMU_DIR > plan.txt

The values come from harness/scenarios.py (parameters, links, step order,
probes); LIBRARY_ROOT/<model>/binaries/linux64/<model>.so are the shared
libraries to load (build.sh's build/<model>/), FMU_DIR holds the .fmu files
whose modelDescription.xml gives value references and types."""
from __future__ import annotations

import sys
from pathlib import Path

from fmpy import read_model_description

from harness.scenarios import COMMUNICATION_STEP, PROBES, SCENARIOS, bench_links

# harness.scenarios.build: instance name -> model, in initialization (data-flow) order
INSTANCES = {"plant": "Pendulum", "controller": "TwistingController",
             "observer": "SuperTwistingObserver"}
STEP_ORDER = ["observer", "plant", "controller"]


def plan(scenario: str, library_root: Path, fmu_dir: Path) -> str:
    s = SCENARIOS[scenario]
    variables, lines = {}, [f"step {COMMUNICATION_STEP!r}"]
    for name, model in INSTANCES.items():
        md = read_model_description(str(fmu_dir / f"{model}.fmu"))
        variables[name] = {v.name: v for v in md.modelVariables}
        library = (library_root / model / "binaries" / "linux64" / f"{model}.so").resolve()
        lines.append(f"fmu {name} {model} {md.guid} {library}")
    for name, values in (("plant", s.plant), ("controller", s.controller),
                         ("observer", s.observer)):
        for variable, value in values.items():
            v = variables[name][variable]
            lines.append(f"{v.type.lower()} {name} {v.valueReference} {float(value)!r}")
    for link in bench_links():
        (src, src_var), (dst, dst_var) = link.source.split(".", 1), link.target.split(".", 1)
        lines.append(f"link {src} {variables[src][src_var].valueReference} "
                     f"{dst} {variables[dst][dst_var].valueReference}")
    lines.append("order " + " ".join(STEP_ORDER))
    for p in PROBES:
        name, variable = p.split(".", 1)
        lines.append(f"probe {name} {variables[name][variable].valueReference}")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sys.stdout.write(plan(sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])))
