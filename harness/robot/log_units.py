"""The units of a robot log's columns: the time in s, ms, us, ns or min, the revolute
joints' positions in rad or deg, the prismatic joints' in m or mm, and the torque
columns as torques (N.m, N) or as drive currents (A) with one drive gain per joint
(N.m/A or N/A: torque = gain x current).  :func:`log_units` turns the options into the
factors that bring each column to s, rad or m, and N.m or N (pint's conversions,
harness.units); the log reader multiplies the columns by them."""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..units import ANGLE_UNITS, LENGTH_UNITS, TIME_UNITS, factor

#: The range of a drive gain's size [N.m/A or N/A]: far beyond any drive's (0.01 to 100
#: with a gearbox), and such that the torques and their squares in the regression stay far
#: inside float64 (a gain of 1e300 overflows them) and the joints' scales within 1e12.
GAIN_RANGE = (1e-6, 1e6)


class UnitError(ValueError):
    """A unit or a gain that cannot be used; the message names the option."""


@dataclass(frozen=True)
class LogUnits:
    """Factors from a robot log's columns to SI: time [s per unit], positions (n,) [rad
    or m per unit], torques (n,) [N.m or N per unit: a drive gain, or 1]."""

    time: float
    position: np.ndarray
    torque: np.ndarray
    time_unit: str | None = None  # as given (None: s by default, not stated)
    angle: float = 1.0   # [rad per unit] of every revolute joint's position column
    length: float = 1.0  # [m per unit] of every prismatic joint's position column

    def of(self, kind: str) -> float:
        """The factor of a position column of a joint of this URDF type (a held joint's:
        "revolute", "continuous" or "prismatic")."""
        return self.length if kind == "prismatic" else self.angle


def parse_gains(text: str) -> tuple[float, ...]:
    """--torque-gains K1,K2,...: finite numbers other than 0, of either sign (a motor
    mounted the other way round, or a current measured with the opposite convention, has
    a negative gain); UnitError names the bad item."""
    items = [item.strip() for item in text.split(",")]
    gains = []
    for k, item in enumerate(items, start=1):
        try:
            value = float(item)
        except ValueError:
            value = math.nan
            if not item:
                raise UnitError(f"--torque-gains {text!r}: gain {k} is empty") from None
        if not (math.isfinite(value) and value != 0.0):
            raise UnitError(f"--torque-gains {text!r}: gain {k} ({item!r}) is not a finite "
                            "number other than 0 (N.m/A of the joint's drive, negative for a "
                            "drive that turns the other way)")
        if not GAIN_RANGE[0] <= abs(value) <= GAIN_RANGE[1]:
            raise UnitError(f"--torque-gains {text!r}: gain {k} ({item!r}) is outside "
                            f"+-{GAIN_RANGE[0]:g} to +-{GAIN_RANGE[1]:g} (N.m/A of the "
                            "joint's drive)")
        gains.append(value)
    return tuple(gains)


def log_units(kinds: Sequence[str], time: str | None = None, angle: str | None = None,
              length: str | None = None, gains: Sequence[float] | None = None,
              held: Sequence[str] = ()) -> LogUnits:
    """The factors for a robot whose joints are `kinds` ("revolute" or "prismatic"):
    `time`, `angle`, `length` the units of the time, the revolute and the prismatic
    joints' position columns (None: s, rad, m); `gains` one drive gain per joint when
    the torque columns hold currents; `held` the kinds of the held joints whose positions
    the log also holds (their columns take the same units).  UnitError names the option
    at fault."""
    def unit(value: str | None, choices: Sequence[str], target: str, option: str) -> float:
        if value is None:
            return 1.0
        if value not in choices:
            raise UnitError(f"{option} {value!r}: expected one of {', '.join(choices)}")
        return factor(value, target)

    seconds = unit(time, TIME_UNITS, "s", "--time-unit")
    radians = unit(angle, ANGLE_UNITS, "rad", "--angle-unit")
    metres = unit(length, LENGTH_UNITS, "m", "--length-unit")
    read = [*kinds, *("prismatic" if kind == "prismatic" else "revolute" for kind in held)]
    if length is not None and "prismatic" not in read:
        raise UnitError(f"--length-unit {length}: the robot has no prismatic joint (the "
                        "revolute joints' unit is --angle-unit)")
    if angle is not None and "revolute" not in read:
        raise UnitError(f"--angle-unit {angle}: the robot has no revolute joint (the "
                        "prismatic joints' unit is --length-unit)")
    position = np.array([metres if kind == "prismatic" else radians for kind in kinds])
    torque = np.ones(len(kinds))
    if gains is not None:
        if len(gains) != len(kinds):
            raise UnitError(f"--torque-gains: {len(gains)} gain(s) for a robot of {len(kinds)} "
                            f"joints; give one per joint, in the order of u1..u{len(kinds)}")
        torque = np.asarray(gains, dtype=float)
        size = np.abs(torque)
        bad = np.flatnonzero(~((size >= GAIN_RANGE[0]) & (size <= GAIN_RANGE[1])))
        if bad.size:
            raise UnitError(f"--torque-gains: gain {bad[0] + 1} ({torque[bad[0]]!r}) is not "
                            f"a number from +-{GAIN_RANGE[0]:g} to +-{GAIN_RANGE[1]:g}")
    return LogUnits(seconds, position, torque, time, radians, metres)
