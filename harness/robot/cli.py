"""`python -m harness identify DATA.csv --robot ROBOT.urdf --out DIR`: the robot options
and command (harness/cli.py dispatches here when --robot is given)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("serial robots (with --robot)")
    group.add_argument("--robot", metavar="URDF",
                       help="identify a serial robot from columns t, q1..qn, u1..un")
    group.add_argument("--lock", action="append", default=[], metavar="JOINT",
                       help="a URDF joint held at 0 (e.g. gripper fingers); repeatable")
    group.add_argument("--unknown", choices=["all", "payload"], default="all",
                       help="all: every base parameter and the friction; payload: the last "
                            "link's parameters and the friction, the other links as in the URDF")
    group.add_argument("--velocity", choices=["sg", "observer"], default="sg",
                       help="sg: zero-phase Savitzky-Golay; observer: the causal "
                            "super-twisting observer of the C core")
    group.add_argument("--window", type=float, default=0.05,
                       help="Savitzky-Golay window [s] (default 0.05)")
    group.add_argument("--min-speed", type=_non_negative, default=None, metavar="V",
                       help="leave out joint equations at |q'| < V [rad/s or m/s], where "
                            "Coulomb friction is not f_c sign(q') (default 0.05)")


def _non_negative(text: str) -> float:
    value = float(text)
    if not value >= 0.0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number >= 0")
    return value


def identify_command(args, out: Path) -> int:
    from .pipeline import LogError, identify_robot, read_log, write_results
    from .urdf import UrdfError, read_urdf
    mapping = {}  # --columns (harness/cli.py) with the roles t, q1..qn, u1..un
    for item in filter(None, (part.strip() for part in args.columns.split(","))):
        name, _, column = item.partition("=")
        if not column.strip():
            print(f"harness identify: --columns item {item!r} is not ROLE=COLUMN", file=sys.stderr)
            return 2
        mapping[name.strip()] = column.strip()
    try:
        robot = read_urdf(args.robot, locked=tuple(args.lock))
        log = read_log(args.data, robot.n, mapping)
        speed = {} if args.min_speed is None else {"min_speed": args.min_speed}
        result = identify_robot(robot, log, unknown=args.unknown, method=args.velocity,
                                window=args.window, **speed)
    except (UrdfError, LogError) as error:
        print(f"harness identify: {error}", file=sys.stderr)
        return 2
    written = write_results(out, robot, log, result, Path(args.data).name)
    print("wrote " + ", ".join(map(str, written)))
    n = robot.n
    for i, joint in enumerate(robot.joints):
        print(f"  {joint.name}: mass {result.pi[10 * i]:.6g} kg, viscous "
              f"{result.pi[10 * n + 2 * i]:.6g}, Coulomb {result.pi[10 * n + 2 * i + 1]:.6g}")
    return 0
