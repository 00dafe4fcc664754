"""The closed loop as an SSP 1.0 file (System Structure and Parameterization).

    python -m harness.ssp FMU_DIR OUT.ssp [--scenario NAME]

The .ssp holds SystemStructure.ssd and the three FMUs under resources/; the
scenario's parameters are bound inline (ssv:ParameterSet) per component.
fmpy's SSP support (fmpy.ssp.ssd.read_ssd, simulate_ssp) loads it.
"""
from __future__ import annotations

import argparse
import sys
import zipfile
from pathlib import Path
from xml.sax.saxutils import quoteattr

from .scenarios import SCENARIOS, Scenario, bench_links

COMPONENTS = {"plant": "Pendulum", "controller": "TwistingController",
              "observer": "SuperTwistingObserver"}
NAMESPACES = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
              'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
              'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"')


def _connectors(component: str) -> list[tuple[str, str]]:
    """(name, kind) of every connector of a component used by a link."""
    found: dict[str, str] = {}
    for link in bench_links():
        for end, kind in ((link.source, "output"), (link.target, "input")):
            fmu, _, variable = end.partition(".")
            if fmu == component:
                found[variable] = kind
    return list(found.items())


def _parameter(name: str, value) -> str:
    if isinstance(value, bool):
        body = f'<ssv:Boolean value="{"true" if value else "false"}"/>'
    elif isinstance(value, int):
        body = f'<ssv:Integer value="{value}"/>'
    else:
        body = f'<ssv:Real value="{float(value)!r}"/>'
    return f'              <ssv:Parameter name={quoteattr(name)}>{body}</ssv:Parameter>'


def system_structure(s: Scenario) -> str:
    parameters = {"plant": s.plant, "controller": s.controller, "observer": s.observer}
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ssd:SystemStructureDescription {NAMESPACES} version="1.0" name="ClosedLoop">',
             f'  <ssd:System name="ClosedLoop" description={quoteattr(s.title)}>',
             '    <ssd:Elements>']
    for component, model in COMPONENTS.items():
        lines.append(f'      <ssd:Component name="{component}" '
                     f'type="application/x-fmu-sharedlibrary" source="resources/{model}.fmu">')
        lines.append('        <ssd:Connectors>')
        for name, kind in _connectors(component):
            lines.append(f'          <ssd:Connector name={quoteattr(name)} kind="{kind}">'
                         f'<ssc:Real/></ssd:Connector>')
        lines.append('        </ssd:Connectors>')
        if parameters[component]:
            lines += ['        <ssd:ParameterBindings>', '          <ssd:ParameterBinding>',
                      '            <ssd:ParameterValues>',
                      f'              <ssv:ParameterSet version="1.0" name="{s.name}">',
                      '              <ssv:Parameters>']
            lines += [_parameter(n, v) for n, v in parameters[component].items()]
            lines += ['              </ssv:Parameters>', '              </ssv:ParameterSet>',
                      '            </ssd:ParameterValues>', '          </ssd:ParameterBinding>',
                      '        </ssd:ParameterBindings>']
        lines.append('      </ssd:Component>')
    lines += ['    </ssd:Elements>', '    <ssd:Connections>']
    for link in bench_links():
        start, _, start_connector = link.source.partition(".")
        end, _, end_connector = link.target.partition(".")
        lines.append(f'      <ssd:Connection startElement="{start}" startConnector='
                     f'{quoteattr(start_connector)} endElement="{end}" endConnector='
                     f'{quoteattr(end_connector)}/>')
    lines += ['    </ssd:Connections>', '  </ssd:System>',
              f'  <ssd:DefaultExperiment startTime="0" stopTime="{s.stop_time!r}"/>',
              '</ssd:SystemStructureDescription>', '']
    return "\n".join(lines)


def write_ssp(fmu_dir: Path, out: Path, scenario: str = "6.2") -> Path:
    s = SCENARIOS[scenario]
    out.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", system_structure(s))
        for model in COMPONENTS.values():
            archive.write(fmu_dir / f"{model}.fmu", f"resources/{model}.fmu")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m harness.ssp")
    parser.add_argument("fmu_dir")
    parser.add_argument("out")
    parser.add_argument("--scenario", default="6.2", choices=list(SCENARIOS))
    args = parser.parse_args(argv)
    print(f"wrote {write_ssp(Path(args.fmu_dir), Path(args.out), args.scenario)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
