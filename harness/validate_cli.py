"""The validate command's parser: ``validate LOG --model MODEL.toml --out DIR`` (the
model files, harness.model.commands) or ``validate LOG --robot URDF --out DIR`` (the
serial robots, harness.robot.validate).  Apart from both, so that building the command
line imports neither (the model files' sympy and pint, the robots' scipy.signal): each
command imports what it runs."""
from __future__ import annotations

import argparse
import math
import sys


def register_validate(sub, parents) -> None:
    """The validate command's parser: a model file (--model) or a serial robot (--robot)."""
    p = sub.add_parser("validate", parents=parents,
                       help="score a model file or a robot's URDF on a log (the cross-test "
                            "of an identified model)",
                       description="With --model: reconstructs each equation's known side "
                       "(the inputs) from the model's nominal values through the zero-phase "
                       "pipeline. With --robot: predicts the log's joint torques by the "
                       "URDF's inverse dynamics (the maker's URDF, or identified.urdf). "
                       "Writes validation.json (relative_error, per equation or joint and "
                       "pooled) and validation.png.")
    p.add_argument("data", metavar="LOG",
                   help="CSV (header row), Parquet (.parquet) or MATLAB .mat")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--model", metavar="MODEL.toml",
                      help="the model file (e.g. an identify run's identified.toml)")
    what.add_argument("--robot", metavar="URDF",
                      help="a serial robot's URDF; the log has columns t, q1..qn, u1..un")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    from .cli import SAMPLE_RATE
    p.add_argument("--sample-rate", type=SAMPLE_RATE, default=None, metavar="HZ",
                   help="the log's samples are evenly spaced at HZ samples per second, and "
                        "no time column is read (a model file's [log] sample_rate says the "
                        "same)")
    robot = p.add_argument_group("serial robots (with --robot)")
    robot.add_argument("--columns", default="", metavar="q1=NAME,...",
                       help="log column of each role t, q1..qn, u1..un")
    robot.add_argument("--window", type=_positive_window, default=None,
                       help="Savitzky-Golay window of the derivatives [s] (default: as "
                            "identify chooses it, from the log's joint velocity windows, "
                            "at least 0.05)")
    robot.add_argument("--joint-terms-file", default=None, metavar="CSV",
                       help="the joint terms (offsets, armature, asymmetric or smooth "
                            "Coulomb) an identify run wrote, added to the URDF's prediction "
                            "(default: joint_terms.csv next to the URDF, if there is one)")
    from .robot.cli import add_chain_arguments, add_unit_arguments
    add_chain_arguments(robot)
    add_unit_arguments(robot, time=True)
    p.set_defaults(func=_validate)


def _positive_window(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f"{text!r} is not a number > 0")
    return value


def _validate(args: argparse.Namespace) -> int:
    if args.robot:
        from .robot.validate import validate_command as validate_robot
        return validate_robot(args)
    given = [option for option, value, default in (
        ("--columns", args.columns, ""), ("--lock", args.lock, []),
        ("--unmeasured", args.unmeasured, None), ("--joints", args.joints, None),
        ("--window", args.window, None), ("--time-unit", args.time_unit, None),
        ("--angle-unit", args.angle_unit, None), ("--length-unit", args.length_unit, None),
        ("--torque-gains", args.torque_gains, None),
        ("--joint-terms-file", args.joint_terms_file, None)) if value != default]
    if given:
        print(f"harness validate: the option(s) {', '.join(given)} go with --robot; a model "
              "file maps its columns in [columns] and gives their units in [units] (t = \"ms\" "
              "for the time)", file=sys.stderr)
        return 2
    from .model.commands import validate_command
    return validate_command(args)
