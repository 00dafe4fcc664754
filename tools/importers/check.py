#!/usr/bin/env python3
"""Run every FMU through independent FMI importers and compare with the reference it ships.

    .venv/bin/python -m tools.importers.check [FMU ...] [--keep DIR] [--tolerance 1e-9]

FMUs default to build/fmus/*.fmu. For each FMU:

  fmpy validate  fmpy.validation.validate_fmu: the XML schema and fmpy's rules
                 (ModelStructure, variable attributes, units, ...); any problem fails
  fmpy           fmpy.simulate_fmu, Co-Simulation, output_interval = stepSize
  FMI4j          tools/importers/fmi4j driver (FMI4j 0.38.0 on Java)
  fmi-sim        `fmi-sim --model FMU -o OUT.csv co-simulation` (Rust, 0.7.0)

Each importer runs the default experiment (startTime to stopTime, a
communication step of stepSize, start values, outputs recorded) and every output
column is compared with the reference result in the FMU
(extra/org.fmi-standard.fmi-ls-ref/, written by make_reference.py) at the
reference's time points: the importer's row at the same time (within 1e-6
stepSize) is taken, and where it has none the column is interpolated linearly
(shown as 'interp' in the table).

Deviation of a column = max |x - ref| / max(1, max |ref|) over the reference
rows; an importer passes when every column's deviation is <= the tolerance
(default 1e-9). The FMUs are deterministic with a fixed internal step locked to
the grid startTime + k*h, and all importers call the same binary at the same
communication points (to a few ulp), so the expected deviation is 0 up to
rounding (~1e-15); 1e-9 leaves six orders of margin for ulp-level differences
in the communication times while anything wrong (a wrong variable, a step
offset, a different step size, a lost start value) gives 1e-6 or more.

Prints a table FMU x importer with the largest deviation or the failure, then
the failures in full, and exits 1 if anything failed (a tool not installed
fails: run tools/importers/install.sh).
"""
from __future__ import annotations

import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree as ET

from tools.importers import make_reference as mr

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

try:
    import numpy as np
except ImportError:
    sys.exit(f"check.py: FAIL: numpy is not importable by {sys.executable}: run "
             f"python -m tools.importers.check with the project's .venv/bin/python (./build.sh creates it)")

CACHE = Path(os.environ.get("STO_TOOLS_CACHE", Path.home() / ".cache" / "sto-tools")).expanduser()
FMI4J = CACHE / "fmi4j"
FMI_SIM = CACHE / "cargo" / "bin" / "fmi-sim"
FMI_SIM_VERSION = "fmi-sim 0.7.0"
INSTALL_HINT = "run tools/importers/install.sh"
IMPORTERS = ("fmpy validate", "fmpy", "FMI4j", "fmi-sim")
TIMEOUT = 900  # seconds per external importer run


class NotInstalled(Exception):
    pass


@dataclass
class Outcome:
    ok: bool
    cell: str                 # short text for the table
    detail: str = ""          # full text for failures
    seconds: float = 0.0


@dataclass
class FmuReport:
    fmu: Path
    outcomes: dict[str, Outcome] = field(default_factory=dict)


# ---- tools -------------------------------------------------------------------------------

def fmi4j_command() -> list[str]:
    classes, lib = FMI4J / "classes", FMI4J / "lib"
    if not (classes / "Fmi4jDriver.class").is_file() or not list(lib.glob("fmi-import-*.jar")):
        raise NotInstalled(f"FMI4j driver not found under {FMI4J}: {INSTALL_HINT}")
    sources = [HERE / "fmi4j" / "pom.xml", HERE / "fmi4j" / "src" / "main" / "java" / "Fmi4jDriver.java",
               HERE / "fmi4j" / "log4j.properties"]
    stamp = (FMI4J / "stamp").read_text().strip() if (FMI4J / "stamp").is_file() else ""
    if shutil.which("javac") is None:
        raise NotInstalled(f"javac not found: {INSTALL_HINT}")
    javac = subprocess.run(["javac", "-version"], capture_output=True, text=True)
    want = hashlib.sha256(b"".join(p.read_bytes() for p in sources)
                          + (javac.stdout + javac.stderr).encode()).hexdigest()
    if stamp != want:
        raise NotInstalled(f"the FMI4j driver in {FMI4J} was built from other sources: {INSTALL_HINT}")
    java = shutil.which("java")
    if java is None:
        raise NotInstalled(f"java not found: {INSTALL_HINT}")
    return [java, f"-Dlog4j.configuration=file:{FMI4J / 'log4j.properties'}",
            "-cp", f"{classes}{os.pathsep}{lib}/*", "Fmi4jDriver"]


def fmi_sim_command() -> list[str]:
    if not os.access(FMI_SIM, os.X_OK):
        raise NotInstalled(f"fmi-sim not found at {FMI_SIM}: {INSTALL_HINT}")
    # It answers --version with "Error: fmi-sim 0.7.0" on stderr and exit status 1.
    answer = subprocess.run([str(FMI_SIM), "--version"], capture_output=True, text=True)
    found = re.search(r"fmi-sim [0-9][0-9.]*", answer.stdout + answer.stderr)
    version = found.group(0) if found else (answer.stdout + answer.stderr).strip()[:80]
    if version != FMI_SIM_VERSION:
        raise NotInstalled(f"{FMI_SIM} is '{version}', expected '{FMI_SIM_VERSION}': {INSTALL_HINT}")
    return [str(FMI_SIM)]


def check_tools() -> list[str]:
    """Problems with the installed importers (empty when all are there)."""
    problems = []
    try:
        import fmpy  # noqa: F401
    except ImportError:
        problems.append(f"fmpy is not importable by {sys.executable}: run python -m tools.importers.check with the "
                        f"project's .venv/bin/python (./build.sh creates it)")
    for probe in (fmi4j_command, fmi_sim_command):
        try:
            probe()
        except NotInstalled as error:
            problems.append(str(error))
    return problems


# ---- comparison --------------------------------------------------------------------------

@dataclass
class Comparison:
    deviation: float
    column: str
    at_time: float
    interpolated: int
    problems: list[str]


def compare(ref: mr.Reference, times, columns: dict, step: float, tolerance: float) -> Comparison:
    """Every reference column against the importer's, at the reference time points."""
    import numpy as np

    problems = []
    times = np.asarray(times, dtype=float)
    if len(times) < 2:
        return Comparison(float("inf"), "", float("nan"), 0, [f"{len(times)} rows"])
    if np.any(np.diff(times) <= 0):
        problems.append("time is not strictly increasing")
        return Comparison(float("inf"), "", float("nan"), 0, problems)
    slack = 1e-6 * step
    if times[0] > ref.times[0] + slack or times[-1] < ref.times[-1] - slack:
        problems.append(f"covers t = {times[0]:.17g} .. {times[-1]:.17g}, the reference "
                        f"{ref.times[0]:.17g} .. {ref.times[-1]:.17g}")
    j = np.clip(np.searchsorted(times, ref.times), 1, len(times) - 1)
    nearest = np.where(np.abs(times[j - 1] - ref.times) <= np.abs(times[j] - ref.times), j - 1, j)
    exact = np.abs(times[nearest] - ref.times) <= slack
    interpolated = int(np.count_nonzero(~exact))
    worst = Comparison(0.0, "", float("nan"), interpolated, problems)
    for name, expected in ref.columns.items():
        if name not in columns:
            problems.append(f"no column '{name}'")
            worst.deviation = float("inf")
            continue
        values = np.asarray(columns[name], dtype=float)
        got = np.where(exact, values[nearest], np.interp(ref.times, times, values))
        both_nan = np.isnan(got) & np.isnan(expected)
        error = np.where(both_nan, 0.0, np.abs(got - expected))
        error = np.where(np.isnan(error), np.inf, error)
        scale = max(1.0, float(np.nanmax(np.abs(expected))) if np.any(np.isfinite(expected)) else 1.0)
        k = int(np.argmax(error))
        deviation = float(error[k]) / scale
        if deviation > worst.deviation or not worst.column:
            worst.deviation, worst.column, worst.at_time = deviation, name, float(ref.times[k])
        if deviation > tolerance:
            problems.append(f"'{name}' deviates by {deviation:.3g} (> {tolerance:g}) at t = "
                            f"{ref.times[k]:.10g}: {float(got[k])!r} vs reference {float(expected[k])!r}")
    return worst


def judged(comparison: Comparison, tolerance: float, seconds: float, extra: str = "") -> Outcome:
    cell = "0" if comparison.deviation == 0 else f"{comparison.deviation:.1e}"
    if comparison.interpolated:
        cell += " interp"
    ok = not comparison.problems and comparison.deviation <= tolerance
    cell += " ok" if ok else " FAIL"
    detail = "; ".join(comparison.problems[:8])
    if len(comparison.problems) > 8:
        detail += f"; ... ({len(comparison.problems)} problems)"
    if extra:
        detail = f"{detail}\n{extra}" if detail else extra
    return Outcome(ok, cell, detail, seconds)


def evaluate(ref: mr.Reference | str, times, columns: dict, step: float | None, tolerance: float,
             seconds: float, extra: str = "") -> Outcome:
    """Compare with the reference, or (no reference: ``ref`` is why) fail after a good run."""
    if isinstance(ref, str):
        detail = f"ran to the end, but there is nothing to compare with: {ref}"
        return Outcome(False, "ran, NO REF", f"{detail}\n{extra}".strip(), seconds)
    # check_fmu passes a Reference only with a stepSize (without one, ``ref`` says so)
    assert step is not None, "a reference, but no stepSize to match its time points with"
    return judged(compare(ref, times, columns, step, tolerance), tolerance, seconds, extra)


def tail(text: str, lines: int = 15) -> str:
    text = text.strip()
    return "\n".join(text.splitlines()[-lines:]) if text else "(no output)"


# ---- importers ---------------------------------------------------------------------------

def run_fmpy_validate(fmu: Path) -> Outcome:
    from fmpy.validation import validate_fmu

    t0 = time.time()
    try:
        problems = validate_fmu(str(fmu))
    except Exception as error:  # noqa: BLE001 - any failure of the validator is a failure
        return Outcome(False, "FAIL", f"validate_fmu raised {type(error).__name__}: {error}")
    if problems:
        return Outcome(False, f"FAIL ({len(problems)})", "\n".join(str(p) for p in problems),
                       time.time() - t0)
    return Outcome(True, "ok", "", time.time() - t0)


def run_fmpy(fmu: Path, desc: mr.Description, ref: mr.Reference | str, tolerance: float) -> Outcome:
    t0 = time.time()
    try:
        times, columns = mr.simulate(fmu, desc)
    except BaseException as error:  # noqa: BLE001 - SystemExit from mr.simulate included
        return Outcome(False, "FAIL", f"fmpy.simulate_fmu: {type(error).__name__}: {error}")
    return evaluate(ref, times, columns, desc.experiment.step, tolerance, time.time() - t0)


class External(threading.Thread):
    """One importer run in the background: stdout dropped (fmi-sim prints a line per
    step), stderr kept in a log; the wall time is the importer's own."""

    def __init__(self, command: list[str], workdir: Path, log: Path):
        super().__init__(daemon=True)
        self.command, self.workdir, self.log = command, workdir, log
        self.code: int | None = None
        self.seconds = 0.0
        self.timed_out = False

    def run(self) -> None:
        t0 = time.time()
        with open(self.log, "wb") as handle:
            try:
                self.code = subprocess.run(self.command, stdout=subprocess.DEVNULL, stderr=handle,
                                           cwd=self.workdir, timeout=TIMEOUT).returncode
            except subprocess.TimeoutExpired:
                self.timed_out = True
            except OSError as error:
                handle.write(f"cannot start {self.command[0]}: {error}\n".encode())
                self.code = -1
        self.seconds = time.time() - t0


def finish(name: str, job: External, out: Path, ref: mr.Reference | str, step: float | None,
           tolerance: float) -> Outcome:
    job.join()
    if job.timed_out:
        return Outcome(False, "FAIL (timeout)", f"{name} did not finish in {TIMEOUT} s", job.seconds)
    messages = job.log.read_text(errors="replace")
    if job.code != 0:
        return Outcome(False, f"FAIL (exit {job.code})",
                       f"{name} exited with {job.code}:\n{tail(messages)}", job.seconds)
    if not out.is_file():
        return Outcome(False, "FAIL (no CSV)", f"{name} wrote no {out.name}:\n{tail(messages)}",
                       job.seconds)
    try:
        _, times, columns = mr.parse_csv(out.read_text(), f"{name} {out.name}")
    except ValueError as error:
        return Outcome(False, "FAIL (CSV)", str(error), job.seconds)
    # FMI4j logs through log4j at WARN and fmi-sim reports on stderr: show what they said.
    extra = f"{name} said:\n{tail(messages, 5)}" if messages.strip() else ""
    return evaluate(ref, times, columns, step, tolerance, job.seconds, extra)


def lenient_step(fmu: Path) -> float | None:
    """DefaultExperiment stepSize read without any schema (for a description fmpy rejects)."""
    try:
        with zipfile.ZipFile(fmu) as archive:
            root = ET.fromstring(archive.read("modelDescription.xml"))
        experiment = root.find("DefaultExperiment")
        step = experiment.get("stepSize") if experiment is not None else None
        return float(step) if step is not None else None
    except Exception:  # noqa: BLE001
        return None


def check_fmu(fmu: Path, workdir: Path, tolerance: float) -> FmuReport:
    report = FmuReport(fmu)
    report.outcomes["fmpy validate"] = run_fmpy_validate(fmu)
    desc: mr.Description | None = None
    step: float | None  # None: no stepSize even in the lenient reading
    every: int | None   # output interval in steps, None: the importer's default
    try:
        desc = mr.read_description(fmu)
        step, every = desc.experiment.step, desc.experiment.decimation
    except (SystemExit, Exception) as error:  # noqa: BLE001 - any failure to read it
        # fmpy cannot read it; the other importers still get their say.
        report.outcomes["fmpy"] = Outcome(False, "FAIL (XML)", f"fmpy cannot read the model "
                                          f"description: {type(error).__name__}: {error}")
        step, every = lenient_step(fmu), None
    ref: mr.Reference | str
    try:
        ref = mr.read_reference(fmu)
    except (LookupError, ValueError, zipfile.BadZipFile) as error:
        ref = str(error)  # the importers still run: whether they can is worth knowing
    if step is None and not isinstance(ref, str):
        ref = "no DefaultExperiment stepSize to match the reference's time points with"
    if step is not None and not isinstance(ref, str) and len(ref.times) > 1:
        every = max(1, round(float(np.min(np.diff(ref.times))) / step))

    # The two external importers run while fmpy simulates in this process (2 cores).
    running = {}
    for name, command_of, args in (
        ("FMI4j", fmi4j_command,
         lambda out: [str(fmu), str(out)]
         + (["--output-interval", repr(every * step)] if every and step else [])),
        ("fmi-sim", fmi_sim_command,
         lambda out: ["--model", str(fmu), "-o", str(out), "co-simulation"]),
    ):
        out = workdir / f"{fmu.stem}.{name}.csv"
        try:
            command = command_of() + args(out)
        except NotInstalled as error:
            report.outcomes[name] = Outcome(False, "NOT INSTALLED", str(error))
            continue
        job = External(command, workdir, workdir / f"{fmu.stem}.{name}.log")
        job.start()
        running[name] = (job, out)

    if desc is not None:
        report.outcomes["fmpy"] = run_fmpy(fmu, desc, ref, tolerance)
    for name, (job, out) in running.items():
        report.outcomes[name] = finish(name, job, out, ref, step, tolerance)
    return report


# ---- main --------------------------------------------------------------------------------

def print_table(reports: list[FmuReport], tolerance: float) -> None:
    width = max(len("FMU"), *(len(r.fmu.stem) for r in reports))
    cols = [max(len(name), *(len(r.outcomes.get(name, Outcome(False, "-")).cell) for r in reports))
            for name in IMPORTERS]
    print(f"\nmax deviation |x - ref| / max(1, max|ref|) per FMU and importer "
          f"(tolerance {tolerance:g}),\nthen the wall time of each run in seconds (FMI4j and fmi-sim run beside fmpy):")
    print("  ".join([f"{'FMU':<{width}}"] + [f"{n:<{w}}" for n, w in zip(IMPORTERS, cols)]))
    for r in reports:
        cells = []
        for name, w in zip(IMPORTERS, cols):
            cells.append(f"{r.outcomes.get(name, Outcome(False, '-')).cell:<{w}}")
        print("  ".join([f"{r.fmu.stem:<{width}}"] + cells))
    print("  ".join([f"{'(seconds)':<{width}}"] + [" " * w for w in cols]).rstrip())
    for r in reports:
        print("  ".join([f"{r.fmu.stem:<{width}}"]
                        + [f"{r.outcomes[n].seconds:<{w}.1f}" if n in r.outcomes else " " * w
                           for n, w in zip(IMPORTERS, cols)]))


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("fmus", nargs="*", type=Path, help="FMUs (default: build/fmus/*.fmu)")
    parser.add_argument("--keep", type=Path, help="keep the importers' CSVs and logs in this directory")
    parser.add_argument("--tolerance", type=float, default=1e-9)
    args = parser.parse_args(argv)

    fmus = args.fmus or sorted((ROOT / "build" / "fmus").glob("*.fmu"))
    if not fmus:
        print(f"check.py: FAIL: no FMUs in {ROOT / 'build' / 'fmus'} (run ./build.sh fmus)", file=sys.stderr)
        return 1
    missing = [f for f in fmus if not f.is_file()]
    if missing:
        print(f"check.py: FAIL: no such FMU: {', '.join(map(str, missing))}", file=sys.stderr)
        return 1
    tools = check_tools()
    for problem in tools:
        print(f"check.py: NOT INSTALLED: {problem}", file=sys.stderr)
    if any("fmpy is not importable" in p for p in tools):
        return 1

    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="sto-importers-") as tmp:
        workdir = args.keep or Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        reports = []
        for fmu in fmus:
            print(f"check.py: {fmu.name} ...", flush=True)
            reports.append(check_fmu(fmu.resolve(), workdir.resolve(), args.tolerance))

    print_table(reports, args.tolerance)
    failures = [(r.fmu.stem, name, o) for r in reports for name, o in r.outcomes.items() if not o.ok]
    notes = [(r.fmu.stem, name, o) for r in reports for name, o in r.outcomes.items() if o.ok and o.detail]
    for stem, name, outcome in notes:
        print(f"\nnote: {stem} / {name}:\n  " + outcome.detail.replace("\n", "\n  "))
    for stem, name, outcome in failures:
        print(f"\nFAIL: {stem} / {name}: {outcome.cell}\n  " + outcome.detail.replace("\n", "\n  "),
              file=sys.stderr)
    total = len(reports) * len(IMPORTERS)
    print(f"\n{len(reports)} FMUs x {len(IMPORTERS)} importers in {time.time() - t0:.1f} s")
    print(f"check.py: {total - len(failures)} passed, {len(failures)} failed")
    if tools:
        print(f"check.py: some importers are not installed: {INSTALL_HINT}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
