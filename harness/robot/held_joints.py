"""Where the joints held out of the chain stand: at a given position, at their logged
position, or at 0.

A held joint is a moving joint of the URDF that is not in the chain: one that --joints
leaves out or that --lock names. Its position is, first to last:

1. the position ``--lock JOINT=POSITION`` gives (``--lock JOINT=0`` holds it at 0);
2. the median of its column in the log: the column ``--columns JOINT=COLUMN`` maps, or
   else the CSV or Parquet column named as the joint (a MATLAB file's variables are not
   looked through: map one with --columns);
3. 0.

A logged joint must have stood still: one whose column spans more than HELD_SPREAD is
refused naming it, since the chain's model would hold still a joint the log shows moving.
The logged position must lie within the joint's ``<limit>``, as a --lock position must.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from ..log_signals import header_of
from .joint_log import HeldColumn, JointLog, LogError
from .urdf import MOVING_TYPES, Robot, read_urdf

#: [rad or m] the most a held joint's logged position may span (its extremes' difference)
#: and still be taken as standing still: 0.057 degrees, 1 mm; a 13-bit or finer encoder
#: flickering between two neighbouring steps stays within it.
HELD_SPREAD = 1e-3


def unit_of(kind: str) -> str:
    """The unit of a joint's position: m for a prismatic joint, else rad."""
    return "m" if kind == "prismatic" else "rad"


def held_without_position(robot: Robot) -> list[str]:
    """The robot's held moving joints that no --lock position places: the ones whose
    logged position is taken when the log holds it."""
    return [name for name in robot.locked if robot.locked_from.get(name) == "default"
            and robot.locked_kinds.get(name) in MOVING_TYPES]


def logged_columns(path: str | Path, robot: Robot, mapping: Mapping[str, str],
                   roles: Sequence[str]) -> list[HeldColumn]:
    """The columns of the log at `path` that hold the positions of the robot's held joints
    without a --lock position: the ones --columns maps (`mapping`, joint -> column), else
    those a CSV or Parquet header names as the joint (never a name that is one of the
    chain's `roles`). LogError for --columns mapping a joint locked at a given position or
    a fixed one (the log's column would be ignored)."""
    wanted = held_without_position(robot)
    for name in mapping:
        if name in robot.locked and name not in wanted:
            why = ("is fixed: it has no position"
                   if robot.locked_kinds.get(name) not in MOVING_TYPES else
                   f"is held at {robot.locked_at[name]:g} by --lock {name}=POSITION")
            raise LogError(f"--columns {name}={mapping[name]}: joint {name!r} {why}; "
                           "leave out one of the two")
    header = header_of(Path(path))  # None for a MATLAB file
    named = set(header) if header is not None and header.present else set()
    found = []
    for name in wanted:
        if name in mapping:
            column = mapping[name]
        elif name in named and name not in roles:
            column = name
        else:
            continue
        found.append(HeldColumn(name, column, robot.locked_kinds[name]))
    return found


def hold_at_logged(robot: Robot, log: JointLog, joints_used: Sequence[str] | None,
                   data: str | Path) -> Robot:
    """The robot read again with each held joint of `log.held` locked at its logged
    position (Robot.locked_from "log"); the robot itself when the log holds none.
    LogError naming the joint and its range for one that moved more than HELD_SPREAD;
    UrdfError for a logged position outside the joint's <limit>."""
    if not log.held:
        return robot
    for name, logged in log.held.items():
        if logged.spread > HELD_SPREAD:
            unit = unit_of(robot.locked_kinds[name])
            raise LogError(
                f"{data}: joint {name!r} is held out of the chain, but its logged position "
                f"(column {logged.column!r}) spans {logged.spread:.3g} {unit} (from "
                f"{logged.low:.6g} to {logged.high:.6g} {unit}), more than {HELD_SPREAD:g} "
                f"{unit}: the chain's model would hold it still. Add it to the chain "
                f"(--joints), or hold it where you choose (--lock {name}=POSITION)")
    locked: dict[str, float | None] = {
        name: log.held[name].position if name in log.held else
        robot.locked_at[name] if robot.locked_from.get(name) == "given" else None
        for name in robot.locked}
    origins = {name: f"its logged position, the median of column {logged.column!r}"
               for name, logged in log.held.items()}
    held = read_urdf(robot.source, locked=locked, gravity=robot.gravity,
                     joints_used=joints_used, origins=origins)
    held.locked_from.update(dict.fromkeys(log.held, "log"))
    return held


def locked_record(robot: Robot, log: JointLog) -> dict[str, dict]:
    """summary.json's held_joints: each held joint's position, where it comes from
    ("given", "log" or "default") and, for a logged one, its column and extremes."""
    record: dict[str, dict] = {}
    for name in robot.locked:
        entry: dict = {"position": robot.locked_at[name],
                       "source": robot.locked_from.get(name, "given")}
        if name in log.held:
            logged = log.held[name]
            entry.update(column=logged.column, low=logged.low, high=logged.high)
        record[name] = entry
    return record


def logged_lines(robot: Robot, log: JointLog) -> list[str]:
    """What the command prints of the joints held at their logged position."""
    lines = []
    for name, logged in log.held.items():
        unit = unit_of(robot.locked_kinds[name])
        lines.append(f"{name}: held at {logged.position:.6g} {unit}, its logged position "
                     f"(median of column {logged.column!r}, which spans {logged.spread:.3g} "
                     f"{unit})")
    return lines
