"""What the user knows of the links' masses, as bounds of the consistent parameters:
a range per link (--mass-range LINK=LO:HI, kg) and the total mass of the chain's moving
bodies (--total-mass KG: every link the joints carry, the links merged into them
included, not the fixed base). Both are linear in the pseudo-inertias, so they join the
convex program of harness.robot.consistency as linear constraints."""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field

from ..values import real
from .urdf import Robot, UrdfError


@dataclass(frozen=True)
class MassBounds:
    """ranges: chain index -> (low, high) kg; total: the chain's total mass, or None."""

    ranges: dict[int, tuple[float, float]] = field(default_factory=dict)
    total: float | None = None

    @property
    def any(self) -> bool:
        return bool(self.ranges) or self.total is not None

    def as_json(self, robot: Robot) -> dict:
        """summary.json's record: each bounded link's range and the total mass."""
        return {"ranges": {robot.joints[i].child_link: list(bounds)
                           for i, bounds in self.ranges.items()}, "total_mass": self.total}


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
                total: float | None) -> MassBounds:
    """The bounds on the robot's chain; UrdfError names a link that is not one of the
    chain's bodies or is given twice, and a total mass that is not finite and > 0."""
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
    return MassBounds(chosen, total)
