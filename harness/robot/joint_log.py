"""A robot's joint log: positions, torques and the clock, read by the one log reader
(harness.log_signals) from CSV, Parquet or MATLAB files with the roles t, q1..qn, u1..un,
and the positions of joints held out of the chain that the log also holds."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..log_signals import Column, LogSignalsError, header_of, read_signals
from .log_units import LogUnits

#: No joint's position [rad or m] or torque [N.m or N] reaches this size; the regression's
#: sums of products of such values would overflow float64 (squares of 1e200 torques made
#: its normal matrix singular).
LARGEST_SAMPLE = 1e12

#: A joint log that cannot be used; the message names the file and line or column.
LogError = LogSignalsError


@dataclass(frozen=True)
class HeldColumn:
    """A held joint's position column to read: the URDF joint, the file's column (a name,
    a 1-based column number or a MATLAB variable) and the joint's URDF type, which gives
    the column's unit (--angle-unit or --length-unit)."""
    joint: str
    column: str
    kind: str


@dataclass(frozen=True)
class LoggedPosition:
    """What a held joint's column says, in rad or m: the median and the extremes."""
    column: str
    position: float
    low: float
    high: float

    @property
    def spread(self) -> float:
        """How far the joint moved over the log (the extremes' difference)."""
        return self.high - self.low


@dataclass
class JointLog:
    t: np.ndarray   # (N,)
    q: np.ndarray   # (N, n)
    u: np.ndarray   # (N, n); 0 for a joint whose torque the log does not hold
    resampled: str | None = None  # what was done to a log whose clock jitters (None: nothing)
    unmeasured: tuple[int, ...] = ()  # those joints (0-based)
    #: the held joints' logged positions, by joint (the columns of read_log's `held`)
    held: dict[str, LoggedPosition] = field(default_factory=dict)

    @property
    def step(self) -> float:
        """The sampling step: the mean step (robust to the rounding of epoch stamps)."""
        return float((self.t[-1] - self.t[0]) / (len(self.t) - 1))

    @property
    def measured(self) -> np.ndarray:
        """(n,) False for the joints whose torque the log does not hold."""
        out = np.ones(self.q.shape[1], dtype=bool)
        out[list(self.unmeasured)] = False
        return out


def read_log(path: str | Path, n: int, mapping: dict[str, str] | None = None,
             relative_tolerance: float = 0.01, units: LogUnits | None = None,
             sample_rate: float | None = None, unmeasured: Sequence[int] = (),
             held: Sequence[HeldColumn] = ()) -> JointLog:
    """Columns t, q1..qn, u1..un (or the names or 1-based column numbers `mapping` gives
    them; a CSV file without a header row has them in that order) of a CSV, Parquet or
    MATLAB log, read by the one log reader (harness.log_signals): a clock whose steps
    differ from the mean step by more than `relative_tolerance` is resampled onto even
    steps, a gap refused.  `units` (harness.robot.log_units) brings the columns to s, rad
    or m and N.m or N (None: they are in these units).  With a `sample_rate` [Hz] no time
    column is read: the samples are evenly spaced at it from t = 0.  The joints
    ``unmeasured`` (0-based) have no torque column (JointLog.unmeasured).  The `held`
    joints' position columns are read with the others (in their joint's unit) and kept as
    their median and extremes (JointLog.held)."""
    path, mapping = Path(path), dict(mapping or {})
    measured = [i for i in range(n) if i not in set(unmeasured)]
    positions, torques = [f"q{i}" for i in range(1, n + 1)], [f"u{i + 1}" for i in measured]
    wanted = ([] if sample_rate is not None else ["t"]) + positions + torques
    if units is not None and len(units.position) != n:
        raise ValueError(f"units for {len(units.position)} joints, the robot has {n}")
    header, hint = header_of(path), f"; needed: {', '.join(wanted)}"
    if header is not None:
        if not header.present and not mapping:
            # no header row: the columns in the roles' order, t, q1..qn, u1..un
            if len(header) != len(wanted):
                raise LogError(f"{path}: no header row and {len(header)} columns; a robot of "
                               f"{n} joints needs {len(wanted)} ({', '.join(wanted)}) or "
                               "--columns with column numbers")
            mapping = {role: str(k + 1) for k, role in enumerate(wanted)}
        found = [k for k in header if k.startswith("q") and k[1:].isdigit()]
        if found and len(found) != n:
            hint += f"; the file has {len(found)} position columns but the robot has {n} joints"
        if len(found) > n and not mapping:
            raise LogError(f"{path}: {len(found)} position columns for a robot of {n} joints")

    def columns(roles: list[str]) -> list[Column]:
        return [Column(role, mapping.get(role, role)) for role in roles]
    # read as positions after q1..qn: the same checks, units and resampling
    held_columns = [Column(column.joint, column.column) for column in held]
    signals = read_signals(
        path, None if sample_rate is not None else Column("t", mapping.get("t", "t")),
        columns(positions) + held_columns, columns(torques), sample_rate=sample_rate,
        time_factor=1.0 if units is None else units.time,
        factors=None if units is None else np.concatenate(
            [units.position, [units.of(column.kind) for column in held],
             units.torque[measured]]),
        missing_hint=hint, tolerance=relative_tolerance,
        slow_step_hint=None if units is not None and units.time_unit is not None else
        "give --time-unit ms (--time-unit s confirms seconds)")
    _check_sizes(path, positions + [column.joint for column in held] + torques,
                 np.concatenate([signals.q, signals.inputs], axis=1))
    u = np.zeros((len(signals.t), n))
    u[:, measured] = signals.inputs
    logged = {column.joint: LoggedPosition(column.column, float(np.median(values)),
                                           float(values.min()), float(values.max()))
              for column, values in zip(held, signals.q[:, n:].T)}
    return JointLog(signals.t, np.ascontiguousarray(signals.q[:, :n]), u, signals.resampled,
                    tuple(i for i in range(n) if i not in measured), logged)


def _check_sizes(path: Path, roles: list[str], values: np.ndarray) -> None:
    """LogError naming each column that reaches LARGEST_SAMPLE in SI units."""
    if not values.size:
        return
    largest = np.max(np.abs(values), axis=0)
    huge = [f"{role} reaches {size:.3g}" for role, size in zip(roles, largest)
            if not size < LARGEST_SAMPLE]
    if huge:
        raise LogError(f"{path}: {', '.join(huge)} (SI units, after the unit options): beyond "
                       f"{LARGEST_SAMPLE:g}, no joint's position or torque; check the column's "
                       "unit or scale (--angle-unit, --length-unit, --torque-gains)")
