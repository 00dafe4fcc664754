"""The closed loop as an SSP 1.0 file (System Structure and Parameterization).

    python -m harness.ssp FMU_DIR OUT.ssp [--scenario NAME]

The .ssp holds SystemStructure.ssd (written with lxml) and the three FMUs
under resources/.  The SSD declares every connector the loop uses plus the
observer's and plant's outputs worth recording (so that a tool records them),
binds the scenario's parameters (ssv:ParameterSet per component) and gives the
experiment: start and stop time, and the communication step as an annotation
(SSP 1.0 has no step size) in the two forms tools read: ``org.sto-harness``
and OSP's ``com.opensimulationplatform`` fixed-step algorithm (libcosim).

fmpy.ssp.simulation.simulate_ssp takes neither the SSD's bindings nor its
experiment (it uses its ``parameter_set``, ``stop_time`` and ``step_size``
arguments, and sets a Boolean from a string as True); :func:`fmpy_arguments`
reads them from the file, typed, for it::

    from fmpy.ssp.simulation import simulate_ssp
    from harness.ssp import fmpy_arguments

    result = simulate_ssp("build/ClosedLoop.ssp", **fmpy_arguments("build/ClosedLoop.ssp"))
"""
from __future__ import annotations

import argparse
import sys
import zipfile
from pathlib import Path
from typing import Any

from lxml import etree

from .inputs import xml_parser
from .scenarios import COMMUNICATION_STEP, SCENARIOS, Scenario, bench_links

COMPONENTS = {"plant": "Pendulum", "controller": "TwistingController",
              "observer": "SuperTwistingObserver"}
SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OSP = "https://opensimulationplatform.com/SSP/OSPAnnotations"
HARNESS = "https://github.com/sto-harness/ssp"  # our annotation's namespace
NAMESPACES = {"ssd": SSD, "ssc": SSC, "ssv": SSV}
# declared on the root: libcosim takes an xmlns attribute on osp:Algorithm for an algorithm
DECLARED = {**NAMESPACES, "osp": OSP, "sto": HARNESS}
# Outputs recorded besides the linked ones (a tool records connectors only).
RECORDED = {
    "plant": ["acceleration", "v", "d"],
    "controller": ["theta_d"],
    "observer": ["x1_hat[1]", "x2_hat[1]", "z_eq_filtered[1]", "theta_hat[1,1]",
                 "theta_hat[1,2]", "theta_hat[1,3]", "gamma_trace"],
}


def connectors(component: str) -> list[tuple[str, str]]:
    """(name, kind) of every connector of a component: the links' ends, then RECORDED."""
    found: dict[str, str] = {}
    for link in bench_links():
        for end, kind in ((link.source, "output"), (link.target, "input")):
            fmu, _, variable = end.partition(".")
            if fmu == component:
                found[variable] = kind
    for variable in RECORDED[component]:
        found.setdefault(variable, "output")
    return list(found.items())


def _q(namespace: str, tag: str) -> str:
    return f"{{{namespace}}}{tag}"


def _parameter(parent, name: str, value: Any) -> None:
    element = etree.SubElement(parent, _q(SSV, "Parameter"), name=name)
    if isinstance(value, bool):
        etree.SubElement(element, _q(SSV, "Boolean"), value="true" if value else "false")
    elif isinstance(value, int):
        etree.SubElement(element, _q(SSV, "Integer"), value=str(value))
    else:
        etree.SubElement(element, _q(SSV, "Real"), value=repr(float(value)))


def system_structure(s: Scenario, step: float = COMMUNICATION_STEP) -> bytes:
    """SystemStructure.ssd of the closed loop with the scenario's parameters."""
    parameters = {"plant": s.plant, "controller": s.controller, "observer": s.observer}
    root = etree.Element(_q(SSD, "SystemStructureDescription"), nsmap=DECLARED,
                         version="1.0", name="ClosedLoop")
    system = etree.SubElement(root, _q(SSD, "System"), name="ClosedLoop", description=s.title)
    elements = etree.SubElement(system, _q(SSD, "Elements"))
    for component, model in COMPONENTS.items():
        element = etree.SubElement(elements, _q(SSD, "Component"), name=component,
                                   type="application/x-fmu-sharedlibrary",
                                   source=f"resources/{model}.fmu")
        holder = etree.SubElement(element, _q(SSD, "Connectors"))
        for name, kind in connectors(component):
            connector = etree.SubElement(holder, _q(SSD, "Connector"), name=name, kind=kind)
            etree.SubElement(connector, _q(SSC, "Real"))
        if parameters[component]:
            binding = etree.SubElement(etree.SubElement(element, _q(SSD, "ParameterBindings")),
                                       _q(SSD, "ParameterBinding"))
            values = etree.SubElement(binding, _q(SSD, "ParameterValues"))
            parameter_set = etree.SubElement(values, _q(SSV, "ParameterSet"), version="1.0",
                                             name=f"{s.name} {component}")
            holder = etree.SubElement(parameter_set, _q(SSV, "Parameters"))
            for name, value in parameters[component].items():
                _parameter(holder, name, value)
    connections = etree.SubElement(system, _q(SSD, "Connections"))
    for link in bench_links():
        start, _, start_connector = link.source.partition(".")
        end, _, end_connector = link.target.partition(".")
        etree.SubElement(connections, _q(SSD, "Connection"), startElement=start,
                         startConnector=start_connector, endElement=end,
                         endConnector=end_connector)
    experiment = etree.SubElement(root, _q(SSD, "DefaultExperiment"), startTime="0",
                                  stopTime=repr(float(s.stop_time)))
    annotations = etree.SubElement(experiment, _q(SSD, "Annotations"))
    ours = etree.SubElement(annotations, _q(SSC, "Annotation"), type="org.sto-harness")
    etree.SubElement(ours, _q(HARNESS, "Experiment"), stepSize=repr(step), scenario=s.name)
    osp = etree.SubElement(annotations, _q(SSC, "Annotation"), type="com.opensimulationplatform")
    algorithm = etree.SubElement(osp, _q(OSP, "Algorithm"))
    etree.SubElement(algorithm, _q(OSP, "FixedStepAlgorithm"), baseStepSize=repr(step))
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


def write_ssp(fmu_dir: Path, out: Path, scenario: str = "6.2") -> Path:
    """The .ssp of a scenario, with the FMUs of ``fmu_dir``: written whole under a
    temporary name, then renamed (harness.outputs); InputError if an FMU is missing,
    OutputError if ``out`` is one of the FMUs or cannot be written."""
    from .inputs import InputError
    from .outputs import Outputs

    s = SCENARIOS[scenario]
    fmus = [Path(fmu_dir) / f"{model}.fmu" for model in COMPONENTS.values()]
    missing = [str(fmu) for fmu in fmus if not fmu.is_file()]
    if missing:
        raise InputError(f"harness.ssp: no FMU {', '.join(missing)} (run ./build.sh fmus, or "
                         f"give the folder of the three FMUs)")
    out = Path(out)
    with Outputs(out.parent, "ssp", inputs=fmus, names=[out.name], lock=False) as outputs:
        with zipfile.ZipFile(outputs.file(out.name), "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("SystemStructure.ssd", system_structure(s))
            for fmu in fmus:
                archive.write(fmu, f"resources/{fmu.name}")
    return out


def fmpy_arguments(ssp: str | Path) -> dict[str, Any]:
    """start_time, stop_time, step_size and parameter_set for fmpy's simulate_ssp, read from
    the file (any SSD with component-level inline ParameterSets), each value in its FMI
    type (fmpy would set a Boolean "false" as True)."""
    from fmpy import read_model_description
    from fmpy.ssp.ssd import Parameter, ParameterSet

    with zipfile.ZipFile(ssp) as archive:
        root = etree.fromstring(archive.read("SystemStructure.ssd"), xml_parser())
        types = {}
        for component in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NAMESPACES):
            with archive.open(component.get("source")) as fmu:
                description = read_model_description(fmu, validate=False)
            types[component.get("name")] = {v.name: v.type for v in description.modelVariables}
    parameter_set = ParameterSet(name="bindings")
    for component in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NAMESPACES):
        name = component.get("name")
        path = ("ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/"
                "ssv:ParameterSet/ssv:Parameters/ssv:Parameter")
        for parameter in component.iterfind(path, NAMESPACES):
            text = parameter[0].get("value")
            kind = types[name][parameter.get("name")]
            value: Any = (text in ("true", "1") if kind == "Boolean" else
                          int(text) if kind in ("Integer", "Enumeration") else float(text))
            parameter_set.parameters.append(Parameter(name=f"{name}.{parameter.get('name')}",
                                                      type=kind, value=value))
    experiment = root.find("ssd:DefaultExperiment", NAMESPACES)
    step = None if experiment is None else experiment.find(f".//{{{HARNESS}}}Experiment")
    if step is None:
        raise ValueError(f"{ssp}: no experiment with a step size (an SSP written by an older "
                         f"harness.ssp? write it again: python -m harness.ssp FMU_DIR OUT.ssp)")
    return {"start_time": float(experiment.get("startTime", 0.0)),
            "stop_time": float(experiment.get("stopTime")),
            "step_size": float(step.get("stepSize")), "parameter_set": parameter_set}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m harness.ssp", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu_dir", help="folder with the three FMUs")
    parser.add_argument("out", help="the .ssp file to write")
    parser.add_argument("--scenario", default="6.2", choices=list(SCENARIOS),
                        help="whose parameters and experiment to bind (default 6.2)")
    args = parser.parse_args(argv)
    from .inputs import InputError
    from .outputs import OutputError, Terminated, shown

    try:
        print(f"wrote {shown(write_ssp(Path(args.fmu_dir), Path(args.out), args.scenario))}")
    except (InputError, OutputError) as error:
        print(error, file=sys.stderr)
        return 2
    except OSError as error:
        print(f"harness.ssp: {args.out}: {error.strerror or error}; nothing was written",
              file=sys.stderr)
        return 2
    except KeyboardInterrupt as interrupt:
        print("\nharness.ssp: interrupted; nothing was written", file=sys.stderr)
        return 143 if isinstance(interrupt, Terminated) else 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
