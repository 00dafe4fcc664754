"""What the user knows of the links' masses, as bounds of the consistent parameters:
a range per link (--mass-range LINK=LO:HI, kg), the total mass of the chain's moving
bodies (--total-mass KG: every link the joints carry, the links merged into them
included, not the fixed base), and each centre of mass inside the box of its body's
shapes (--com-in-geometry; harness.robot.geometry). All are linear in the
pseudo-inertias, so they join the convex program of harness.robot.consistency as linear
constraints."""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field

import numpy as np

from ..values import real
from .geometry import Box, com_boxes
from .urdf import Robot, UrdfError, body_inertial


@dataclass(frozen=True)
class MassBounds:
    """ranges: chain index -> (low, high) kg; total: the chain's total mass, or None;
    com_boxes: chain index -> the box (joint frame, m) its centre of mass must lie in,
    and without_box: body link -> why it has none (when the boxes were asked for)."""

    ranges: dict[int, tuple[float, float]] = field(default_factory=dict)
    total: float | None = None
    com_boxes: dict[int, Box] = field(default_factory=dict)
    without_box: dict[str, str] = field(default_factory=dict)

    @property
    def any(self) -> bool:
        return bool(self.ranges) or self.total is not None or bool(self.com_boxes)

    def as_json(self, robot: Robot) -> dict:
        """summary.json's record: each bounded link's range, the total mass, each centre
        of mass's box and the bodies left without one."""
        return {"ranges": {robot.joints[i].child_link: list(bounds)
                           for i, bounds in self.ranges.items()}, "total_mass": self.total,
                "com_boxes": {robot.joints[i].child_link: {"low": low.tolist(),
                                                           "high": high.tolist()}
                              for i, (low, high) in self.com_boxes.items()},
                "without_com_box": dict(self.without_box)}

    def urdf_outside(self, robot: Robot) -> list[str]:
        """The bodies whose URDF centre of mass lies outside their box."""
        out = []
        for i, (low, high) in self.com_boxes.items():
            mass, com, _ = body_inertial(robot.joints[i].link)
            if mass > 0 and (np.any(com < low) or np.any(com > high)):
                out.append(robot.joints[i].child_link)
        return out


def parse_mass_range(text: str) -> tuple[str, float, float]:
    """--mass-range LINK=LO:HI (kg; 0 <= LO <= HI, finite)."""
    name, sign, span = text.partition("=")
    low, colon, high = span.partition(":")
    if not name.strip() or not sign or not colon:
        raise argparse.ArgumentTypeError(f"{text!r}: expected LINK=LOW:HIGH in kg, e.g. "
                                          f"forearm=3.0:4.5")
    try:
        lo = real(f"--mass-range {name.strip()} low", low.strip())
        hi = real(f"--mass-range {name.strip()} high", high.strip())
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo <= hi):
        raise argparse.ArgumentTypeError(f"--mass-range {text}: the range must be finite "
                                          f"with 0 <= LOW <= HIGH")
    return name.strip(), lo, hi


def mass_bounds(robot: Robot, ranges: list[tuple[str, float, float]],
                total: float | None, com_in_geometry: bool = False) -> MassBounds:
    """The bounds on the robot's chain (with com_in_geometry, each body's centre of mass
    inside the box of its shapes, where it has one); UrdfError names a link that is not
    one of the chain's bodies or is given twice, and a total mass that is not finite and
    > 0."""
    links = [joint.child_link for joint in robot.joints]
    chosen: dict[int, tuple[float, float]] = {}
    for name, lo, hi in ranges:
        if name not in links:
            raise UrdfError(f"--mass-range {name}: not one of the chain's bodies (the links "
                            f"the moving joints carry: {', '.join(links)})")
        index = links.index(name)
        if index in chosen:
            raise UrdfError(f"--mass-range {name} is given twice")
        chosen[index] = (lo, hi)
    if total is not None and not (math.isfinite(total) and total > 0):
        raise UrdfError(f"--total-mass {total!r}: a finite mass > 0 in kg")
    if total is not None and chosen:
        low = sum(lo for lo, _ in chosen.values())
        high = (sum(hi for _, hi in chosen.values()) if len(chosen) == len(links)
                else math.inf)
        if not low <= total <= high:
            raise UrdfError(f"--total-mass {total:g} kg cannot be met within the "
                            f"--mass-range bounds (together {low:g} to {high:g} kg)")
    boxes, without = com_boxes(robot) if com_in_geometry else ({}, {})
    return MassBounds(chosen, total, boxes, without)
