#!/usr/bin/env python3
"""Compute an FMU's reference result with fmpy and ship it inside the FMU (FMI-LS-REF).

    python tools/importers/make_reference.py build/fmus/X.fmu [...]   embed into X.fmu (in place)
    python tools/importers/make_reference.py build/X [...]            FMU directory: write the files into it
    python tools/importers/make_reference.py --csv OUT.csv X.fmu      only write the CSV

The reference is the FMU's own default experiment: Co-Simulation from
DefaultExperiment startTime to stopTime, communicating every stepSize (fmpy's
``simulate_fmu`` with output_interval = stepSize), all outputs recorded.

Layout, as in the FMI Layered Standard References (FMI-LS-REF 1.0.0-alpha.1) and
the Modelica Reference FMUs (``BouncingBall_out.csv``, role ``result``):

    extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml   <fmiReferences> with one
        <Related type="text/csv" source="<modelName>_out.csv" role="result" .../>
    extra/org.fmi-standard.fmi-ls-ref/<modelName>_out.csv   the result
    documentation/fmi-ls-ref.txt                            what the result is (recommended by the standard)

CSV: header ``time,<output names in modelDescription order>`` (names quoted when
they contain a comma, RFC 4180; an FMI 3 array output as one column per element,
named as FMI 2 names the elements: ``x[2]``, ``A[1,3]``, row-major, so that the
FMI 2 and FMI 3 variants of a model have the same columns), one row per output point, values as the shortest
decimal that reads back to the same double (Python repr), Booleans as 1/0.
Rows: the state after initialization and every ``decimation``-th communication
point up to and including stopTime, ``decimation = ceil(steps / MAX_INTERVALS)``,
so that a run of 10^6 steps ships 1001 rows and not 10^6 (every row is still an
exact communication point of the default experiment, not an interpolation).

Rewriting is idempotent: earlier FMI-LS-REF members are replaced, every other
member is copied unchanged, and the new members get the timestamp of
modelDescription.xml, so that a second run gives a byte-identical FMU.
"""
from __future__ import annotations

import argparse
import csv
import io
import math
import os
import stat
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from xml.etree import ElementTree as ET

if TYPE_CHECKING:  # numpy loads on first use, not with the module
    import numpy as np

LS_REF_DIR = "extra/org.fmi-standard.fmi-ls-ref"
MANIFEST = f"{LS_REF_DIR}/fmi-ls-manifest.xml"
DOC = "documentation/fmi-ls-ref.txt"
LS_NS = "http://fmi-standard.org/fmi-ls-manifest"
LS_VERSION = "1.0.0-alpha.1"
RESULT_ROLE = "result"
MAX_INTERVALS = 1000


@dataclass
class Experiment:
    start: float
    stop: float
    step: float
    tolerance: float | None

    @property
    def steps(self) -> int:
        n = round((self.stop - self.start) / self.step)
        if n < 1 or abs((self.stop - self.start) / self.step - n) > 1e-6:
            raise SystemExit(f"stopTime - startTime = {self.stop - self.start} is not a multiple "
                             f"of stepSize = {self.step}")
        return n

    @property
    def decimation(self) -> int:
        return max(1, math.ceil(self.steps / MAX_INTERVALS))

    @property
    def output_interval(self) -> float:
        return self.decimation * self.step


@dataclass
class Description:
    model_name: str
    fmi_version: str  # "2.0" or "3.0"
    outputs: list[tuple[str, str, tuple[int, ...]]]  # (name, type, array shape) in order
    experiment: Experiment

    @property
    def columns(self) -> list[tuple[str, str, str, tuple[int, ...]]]:
        """(column name, type, variable name, element index) of every output element."""
        import itertools

        result = []
        for name, type_, shape in self.outputs:
            for index in itertools.product(*(range(n) for n in shape)):
                label = f"{name}[{','.join(str(i + 1) for i in index)}]" if shape else name
                result.append((label, type_, name, index))
        return result


def read_description(fmu: Path) -> Description:
    """Model name, outputs and default experiment, read with fmpy."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    de = md.defaultExperiment
    if de is None or de.stopTime is None or de.stepSize is None:
        raise SystemExit(f"{fmu}: the DefaultExperiment needs stopTime and stepSize")
    exp = Experiment(float(de.startTime or 0.0), float(de.stopTime), float(de.stepSize),
                     float(de.tolerance) if de.tolerance is not None else None)
    outputs = [(v.name, v.type, tuple(v.shape or ())) for v in md.modelVariables
               if v.causality == "output"]
    if not outputs:
        raise SystemExit(f"{fmu}: no outputs to record")
    if md.coSimulation is None:
        raise SystemExit(f"{fmu}: no Co-Simulation interface")
    return Description(md.modelName, md.fmiVersion, outputs, exp)


def result_name(desc: Description) -> str:
    return f"{desc.model_name}_out.csv"


def simulate(fmu: Path, desc: Description):
    """The default experiment with fmpy: (times, {name: values}) at every communication point."""
    import numpy as np
    from fmpy import simulate_fmu

    exp = desc.experiment
    result = simulate_fmu(str(fmu), fmi_type="CoSimulation", start_time=exp.start,
                          stop_time=exp.stop, output_interval=exp.step,
                          relative_tolerance=exp.tolerance,
                          output=[name for name, _, _ in desc.outputs])
    if len(result) != exp.steps + 1:
        raise SystemExit(f"{fmu}: fmpy returned {len(result)} rows for {exp.steps} steps")
    columns = {name: np.asarray(result[name], dtype=float) for name, _, _ in desc.outputs}
    return np.asarray(result["time"], dtype=float), columns


def format_value(x, type_: str) -> str:
    """Shortest text that reads back to the same double; Integer and Boolean as integers."""
    if type_ in ("Integer", "Boolean", "Enumeration") or "Int" in type_:
        return str(int(x))
    return repr(float(x))


def reference_csv(desc: Description, times, columns) -> str:
    """The reference CSV text: decimated rows of the default experiment."""
    exp = desc.experiment
    n, every = exp.steps, exp.decimation
    rows = list(range(0, n + 1, every))
    if rows[-1] != n:
        rows.append(n)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["time"] + [label for label, _, _, _ in desc.columns])
    for k in rows:
        t = exp.stop if k == n else exp.start + k * exp.step
        writer.writerow([f"{t:.15g}"] + [format_value(columns[name][k][index], type_)
                                         for _, type_, name, index in desc.columns])
    return out.getvalue()


def manifest_xml(desc: Description) -> str:
    exp = desc.experiment
    ET.register_namespace("fmi-ls", LS_NS)
    root = ET.Element("fmiReferences", {
        f"{{{LS_NS}}}fmi-ls-name": "org.fmi-standard.fmi-ls-ref",
        f"{{{LS_NS}}}fmi-ls-version": LS_VERSION,
        f"{{{LS_NS}}}fmi-ls-description":
            "Layered Standard providing information on related files included in an FMU.",
    })
    ET.SubElement(root, "Related", {
        "type": "text/csv",
        "source": result_name(desc),
        "role": RESULT_ROLE,
        "description": (f"Output of the default experiment: Co-Simulation from {exp.start:g} s to "
                        f"{exp.stop:g} s communicating every {exp.step:g} s (fmpy), outputs every "
                        f"{exp.output_interval:g} s"),
    })
    ET.SubElement(root, "Related", {
        "type": "text/plain",
        "source": "../../documentation/fmi-ls-ref.txt",
        "role": "document",
        "description": "How the reference result was made and how to compare with it",
    })
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def documentation(desc: Description) -> str:
    exp = desc.experiment
    if desc.fmi_version.startswith("2"):
        setup = f"setupExperiment(startTime = {exp.start:g}, stopTime = {exp.stop:g}),\nthen fmi2DoStep"
    else:
        setup = (f"fmi3EnterInitializationMode(startTime = {exp.start:g}, stopTime = {exp.stop:g}),"
                 f"\nthen fmi3DoStep")
    return f"""Reference result of {desc.model_name} (FMI-LS-REF {LS_VERSION})

{LS_REF_DIR}/{result_name(desc)} is the output of this FMU's default experiment:
FMI {desc.fmi_version} Co-Simulation, {setup} at the communication points startTime + k * {exp.step:g} s
({exp.steps} steps, the last one ending exactly at stopTime), no inputs set (start values),
computed with fmpy's simulate_fmu.

Rows: after initialization, then every {exp.decimation}th communication point
(every {exp.output_interval:g} s) and stopTime. Columns: time, then the {len(desc.columns)} output
elements in modelDescription.xml order (an array output as one column per element, x[i] or
A[i,j], row-major); Booleans as 1/0; values printed to round-trip exactly.

The FMU is deterministic with a fixed internal step, so any importer that communicates
at these points should reproduce every value to rounding: the project's CI
(tools/importers/check.py) accepts |value - reference| <= 1e-9 * max(1, max|reference column|).
"""


def members(desc: Description, csv_text: str) -> dict[str, bytes]:
    return {
        MANIFEST: manifest_xml(desc).encode(),
        f"{LS_REF_DIR}/{result_name(desc)}": csv_text.encode(),
        DOC: documentation(desc).encode(),
    }


def is_ls_ref_member(name: str) -> bool:
    return name.startswith(LS_REF_DIR + "/") or name == DOC


def embed_in_archive(fmu: Path, new: dict[str, bytes]) -> None:
    """Rewrite ``fmu`` with ``new`` replacing any earlier FMI-LS-REF members."""
    with zipfile.ZipFile(fmu) as src:
        infos = [i for i in src.infolist() if not is_ls_ref_member(i.filename)]
        stamp = src.getinfo("modelDescription.xml").date_time
        fd, tmp = tempfile.mkstemp(prefix=fmu.name, suffix=".tmp", dir=fmu.parent)
        os.close(fd)
        try:
            os.chmod(tmp, stat.S_IMODE(os.stat(fmu).st_mode))  # mkstemp makes it 0600
            with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
                for info in infos:
                    dst.writestr(info, src.read(info.filename))
                for name, data in new.items():
                    info = zipfile.ZipInfo(name, date_time=stamp)
                    info.compress_type = zipfile.ZIP_DEFLATED
                    info.external_attr = 0o644 << 16
                    dst.writestr(info, data)
            os.replace(tmp, fmu)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise


def embed_in_directory(directory: Path, new: dict[str, bytes]) -> None:
    for name, data in new.items():
        path = directory / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)


def make_reference(fmu: Path, csv_out: Path | None = None) -> str:
    desc = read_description(fmu)
    times, columns = simulate(fmu, desc)
    text = reference_csv(desc, times, columns)
    if csv_out is not None:
        csv_out.write_text(text)
        return f"{fmu}: wrote {csv_out}"
    new = members(desc, text)
    if fmu.is_dir():
        embed_in_directory(fmu, new)
    else:
        embed_in_archive(fmu, new)
    rows = text.count("\n") - 1
    return (f"{fmu}: reference {LS_REF_DIR}/{result_name(desc)} ({rows} rows x "
            f"{len(desc.columns)} outputs, every {desc.experiment.output_interval:g} s)")


# ---- reading, for check.py -----------------------------------------------------------

@dataclass
class Reference:
    source: str
    header: list[str]
    times: np.ndarray                # float, one per row
    columns: dict[str, np.ndarray]   # column name -> its float values, one per row


def parse_csv(text: str, origin: str) -> tuple[list[str], np.ndarray, dict[str, np.ndarray]]:
    """(header, times, {name: values}) of a CSV whose first column is time; true/false -> 1/0."""
    import numpy as np

    first, _, body = text.partition("\n")
    try:
        header = [h.strip() for h in next(csv.reader([first]))]
    except StopIteration:
        raise ValueError(f"{origin}: empty CSV") from None
    if not header or header[0] != "time":
        raise ValueError(f"{origin}: the first column is {header[:1]}, not time")
    body = body.replace("true", "1").replace("false", "0")
    try:
        array = np.loadtxt(io.StringIO(body), delimiter=",", dtype=float, ndmin=2)
    except ValueError as error:
        raise ValueError(f"{origin}: {error}") from None
    if array.shape[0] == 0:
        raise ValueError(f"{origin}: no data rows")
    if array.shape[1] != len(header):
        raise ValueError(f"{origin}: {array.shape[1]} fields per row, header has {len(header)}")
    return header, array[:, 0], {name: array[:, i] for i, name in enumerate(header) if i > 0}


def read_reference(fmu: Path) -> Reference:
    """The result the FMU ships under FMI-LS-REF (found through the manifest)."""
    with zipfile.ZipFile(fmu) as archive:
        names = set(archive.namelist())
        if MANIFEST not in names:
            raise LookupError(f"{fmu}: no {MANIFEST} (run tools/importers/make_reference.py {fmu})")
        root = ET.fromstring(archive.read(MANIFEST))
        sources = [r.get("source") for r in root.iter("Related")
                   if r.get("role") == RESULT_ROLE and r.get("source")]
        if not sources:
            raise LookupError(f"{fmu}: {MANIFEST} declares no Related file with role '{RESULT_ROLE}'")
        member = os.path.normpath(f"{LS_REF_DIR}/{sources[0]}").replace(os.sep, "/")
        if member not in names:
            raise LookupError(f"{fmu}: {MANIFEST} names {sources[0]}, which the archive lacks")
        text = archive.read(member).decode()
    header, times, columns = parse_csv(text, f"{fmu}!{member}")
    return Reference(member, header, times, columns)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("fmus", nargs="+", type=Path, help="FMU archives or FMU directories")
    parser.add_argument("--csv", type=Path, help="only write the reference CSV here (one FMU)")
    args = parser.parse_args(argv)
    if args.csv and len(args.fmus) != 1:
        parser.error("--csv takes exactly one FMU")
    for fmu in args.fmus:
        if not fmu.exists():
            print(f"make_reference: no such FMU: {fmu}", file=sys.stderr)
            return 1
        print(make_reference(fmu, args.csv))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
