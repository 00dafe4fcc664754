"""Offline identification: a recorded experiment (t, y, u) fed through the observer FMU."""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .fmus import FMUInstance, Value
from .master import CoSimulation, Link, initialize, run

REQUIRED = ("t", "y", "u")
OUTPUTS = ["x1_hat[1]", "x2_hat[1]", "z_eq[1]", "z_eq_filtered[1]"] + \
          [f"theta_hat[1,{k}]" for k in range(1, 6)] + \
          [f"theta_std[1,{k}]" for k in range(1, 6)] + \
          ["b_hat", "b_std", "gamma_trace", "noise_std[1]", "observer_bandwidth[1]"]


class DataError(ValueError):
    """The recorded data cannot be used; the message names the file and line."""


@dataclass
class Recording:
    t: np.ndarray
    y: np.ndarray
    u: np.ndarray

    @property
    def step(self) -> float:
        return float(self.t[1] - self.t[0])


def read_recording(path: str | Path, relative_tolerance: float = 1e-6) -> Recording:
    """Read columns t, y, u (header row, any order, extra columns ignored) with clear errors.

    The file is UTF-8 text (a byte-order mark, as spreadsheets write for "CSV UTF-8",
    is skipped); anything else -- another encoding, a binary file, a field too long
    for a CSV reader -- is a DataError that names the file and line, never a
    traceback."""
    path = Path(path)
    try:
        handle = path.open(newline="", encoding="utf-8-sig")
    except OSError as error:
        raise DataError(f"{path}: cannot open ({error.strerror})") from None
    reader = None
    try:
        with handle:
            reader = csv.reader(handle)
            return _parse_recording(path, reader, relative_tolerance)
    except UnicodeDecodeError:
        raise DataError(f"{path}: {_not_utf8(path)}; identify reads UTF-8 text (save the file "
                        f"as CSV UTF-8)") from None
    except csv.Error as error:
        line = reader.line_num if reader is not None else 0
        raise DataError(f"{path} line {line}: not a readable CSV file ({error}); identify needs "
                        f"a text CSV with a header t, y, u") from None
    except OSError as error:
        raise DataError(f"{path}: cannot read ({error.strerror or error})") from None


def _not_utf8(path: Path) -> str:
    """Where the file stops being UTF-8: its first bad byte, with line and offset."""
    data = path.read_bytes()
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as error:
        line = data.count(b"\n", 0, error.start) + 1
        return (f"line {line}: byte 0x{data[error.start]:02x} at offset {error.start} is not "
                f"UTF-8")
    return "not UTF-8"


def _parse_recording(path: Path, reader, relative_tolerance: float) -> Recording:
    header = next(reader, None)
    if header is None:
        raise DataError(f"{path}: the file is empty")
    names = [h.strip().lower() for h in header]
    missing = [c for c in REQUIRED if c not in names]
    if missing:
        raise DataError(f"{path} line 1: missing column(s) {', '.join(missing)}; the header "
                        f"must name t, y and u (found: {', '.join(header) or 'nothing'})")
    columns = {c: names.index(c) for c in REQUIRED}
    rows: list[tuple[float, float, float]] = []
    for line, row in enumerate(reader, start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        values = []
        for name in REQUIRED:
            index = columns[name]
            if index >= len(row):
                raise DataError(f"{path} line {line}: column {name!r} is missing "
                                f"({len(row)} fields)")
            text = row[index].strip()
            try:
                value = float(text)
            except ValueError:
                raise DataError(f"{path} line {line}: {name} = {text!r} is not a number") \
                    from None
            if not math.isfinite(value):
                raise DataError(f"{path} line {line}: {name} = {text} is not finite "
                                f"(NaN or Inf rows must be removed or interpolated first)")
            values.append(value)
        rows.append((values[0], values[1], values[2]))
    if len(rows) < 3:
        raise DataError(f"{path}: {len(rows)} data row(s); at least 3 are needed")
    data = np.array(rows)
    t = data[:, 0]
    dt = np.diff(t)
    step = dt[0]
    if not step > 0:
        raise DataError(f"{path} line 3: time does not increase (t = {t[0]!r}, then {t[1]!r})")
    bad = np.nonzero(np.abs(dt - step) > relative_tolerance * max(abs(step), 1e-300) +
                     4 * np.finfo(float).eps * np.abs(t[1:]))[0]
    if bad.size:
        i = int(bad[0])
        raise DataError(f"{path} line {i + 3}: sampling step {dt[i]!r} differs from the first "
                        f"step {step!r}; identify needs uniform sampling (resample first)")
    return Recording(t, data[:, 1], data[:, 2])


INPUT_HOLDS = ("zoh", "sampled")


def held_input(u: np.ndarray, input_hold: str) -> np.ndarray:
    """The input as the FMU takes it: constant over each sample interval (FMI's
    piecewise-constant inputs).

    ``"zoh"``: u[k] was applied over [t_k, t_k+1) (a digital controller's
    command).  ``"sampled"``: u[k] is a sample of a continuous signal (a measured
    torque, a plant driven by a smooth input); its mean over [t_k, t_k+1) is
    (u[k] + u[k+1]) / 2 to O(h^2).  Taking a sampled input as held shifts it by
    half a sample, which biases the identified viscous coefficient by O(h)
    (measured: 13.7 % at 1 kHz, open-loop multi-sine)."""
    if input_hold == "zoh":
        return u
    if input_hold == "sampled":
        return np.concatenate([0.5 * (u[:-1] + u[1:]), u[-1:]])
    raise ValueError(f"input_hold = {input_hold!r}: expected one of {', '.join(INPUT_HOLDS)}")


def identify(recording: Recording, observer_fmu: Path, parameters: dict[str, Value],
             input_hold: str = "zoh") -> dict[str, np.ndarray]:
    """Run the observer over the recording; returns t, y, u and the observer outputs.

    ``input_hold`` says how u was applied between samples (see held_input)."""
    observer = FMUInstance(observer_fmu, "observer")
    sim = CoSimulation({"observer": observer},
                       [Link("signal:y", "observer.y[1]"), Link("signal:u", "observer.u")])
    parameters = {"h": default_internal_step(recording.step, observer.variable("h").max),
                  **parameters}
    n = len(recording.t) - 1
    signals = {"y": recording.y[:n], "u": held_input(recording.u, input_hold)[:n]}
    try:
        initialize(sim, float(recording.t[0]), {"observer": parameters}, signals)
        records = run(sim, float(recording.t[0]), float(recording.t[0]) + n * recording.step,
                      recording.step, [f"observer.{o}" for o in OUTPUTS], signals=signals)
    finally:
        sim.close()
    # the recording's own time stamps (the master's t0 + k H may differ in the last bit)
    out = {"t": recording.t[: len(records.time)], "y": recording.y[: len(records.time)],
           "u": recording.u[: len(records.time)]}
    for name in OUTPUTS:
        out[name.replace("[1]", "")] = records[f"observer.{name}"]
    return out


def largest_internal_step(observer_fmu: Path) -> float | None:
    """The largest h the observer FMU declares (its variable h's max)."""
    from fmpy import read_model_description

    from .fmus import variables_of

    return variables_of(read_model_description(str(observer_fmu)))["h"].max


def default_internal_step(step: float, h_max: float | None) -> float:
    """The observer's h when the user gives none: the sample step itself
    (sub-stepping would hold y constant over a sample, a staircase the observer
    then tracks), or, for samples further apart than the largest h the FMU
    accepts (``h_max``, 1 s), the sample step split into the fewest equal
    internal steps that fit."""
    if h_max is None or step <= h_max:
        return step
    return step / math.ceil(step / h_max)


def final_estimates(columns: dict[str, np.ndarray]) -> dict[str, object]:
    """The estimates at the end of the record with their standard errors (1 sigma) and
    the estimated measurement noise: what ``identify`` writes to estimates.json."""
    names = [f"theta_hat[1,{k}]" for k in range(1, 6)] + ["b_hat"]
    errors = [f"theta_std[1,{k}]" for k in range(1, 6)] + ["b_std"]
    return {"final": {n: float(columns[n][-1]) for n in names},
            "standard_error": {n: float(columns[e][-1]) for n, e in zip(names, errors)},
            "noise_std": float(columns["noise_std"][-1])}


def write_csv(columns: dict[str, np.ndarray], path: Path) -> None:
    """The columns as CSV, every number at full precision (%.17g round-trips a
    double: epoch timestamps at 1 kHz stay distinct)."""
    names = list(columns)
    np.savetxt(path, np.column_stack([columns[n] for n in names]), delimiter=",",
               header=",".join(names), comments="", fmt="%.17g")
