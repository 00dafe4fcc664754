"""`python -m harness identify DATA.csv --robot ROBOT.urdf --out DIR`: the robot options
and command (harness/cli.py dispatches here when --robot is given); and
`python -m harness robot-fmu-parameters ROBOT.urdf --out FILE.ssv`."""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ..messages import note
from ..names import plain
from ..units import ANGLE_UNITS, LENGTH_UNITS, TIME_UNITS
from ..values import argparse_type, real
from .mass_bounds import mass_bounds, parse_mass_range


def add_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("serial robots (with --robot)")
    group.add_argument("--robot", metavar="URDF",
                       help="identify a serial robot from columns t, q1..qn, u1..un")
    add_chain_arguments(group)
    group.add_argument("--unknown", choices=["all", "payload"], default="all",
                       help="all: every base parameter and the friction; payload: the last "
                            "link's parameters and the friction, the other links as in the URDF")
    group.add_argument("--velocity", choices=["sg", "observer"], default="sg",
                       help="sg: zero-phase Savitzky-Golay; observer: a causal, model-free "
                            "observer per joint (the observer FMU's default estimator: "
                            "implicit super-twisting + noise-adaptive linear observers, C "
                            "core) and a momentum-form regression through a causal filter")
    group.add_argument("--window", type=_positive("--window"), default=None,
                       help="the regression's Savitzky-Golay window [s] (> 0; default: the "
                            "longest of the joints' velocity windows, which follow the "
                            "encoder's noise, at least 0.05)")
    group.add_argument("--min-speed", type=_non_negative, default=None, metavar="V",
                       help="leave out joint equations at |q'| < V [rad/s or m/s], where "
                            "Coulomb friction is not f_c sign(q') (default 0.05)")
    group.add_argument("--urdf-tolerance", type=_positive("--urdf-tolerance"), default=None,
                       metavar="FRACTION",
                       help="how far the URDF's masses, inertias and friction are trusted, "
                            "relative (0.3: within +-30 %%, the default): the prior that "
                            "picks the physically consistent parameters the data leave open; "
                            "it never moves them out of the estimate's confidence region")
    group.add_argument("--mass-range", action="append", type=parse_mass_range, default=[],
                       metavar="LINK=LOW:HIGH",
                       help="a link's mass known to lie in [LOW, HIGH] kg: the physically "
                            "consistent model is held to it; LINK is a body the chain's "
                            "joints carry (summary.json's masses); repeatable")
    group.add_argument("--total-mass", type=_positive("--total-mass"), default=None,
                       metavar="KG",
                       help="the chain's moving bodies weigh KG together (the fixed base "
                            "left out): the physically consistent model is held to it")
    group.add_argument("--com-in-geometry", action="store_true",
                       help="hold each body's centre of mass inside the box of its links' "
                            "shapes (the URDF's <collision>, else <visual>: boxes, "
                            "cylinders, spheres, meshes); a body without readable shapes "
                            "is named and left unbounded")
    group.add_argument("--joint-terms", default=None, metavar="TERM,...",
                       help="extra terms of every joint, identified with the rest: offset "
                            "(a constant torque), armature (reflected rotor inertia, x q''), "
                            "asymmetric-coulomb (a Coulomb level per direction), none, or "
                            "auto (the combination of these the log supports, by "
                            "cross-validation: the default, unless --smooth-coulomb is "
                            "given); written to DIR/joint_terms.csv, which validate --robot "
                            "reads")
    group.add_argument("--smooth-coulomb", type=_positive("--smooth-coulomb"), default=None,
                       metavar="VS",
                       help="Coulomb friction as fc tanh(q'/VS) instead of fc sign(q') "
                            "[VS in rad/s or m/s, > 0]")
    add_unit_arguments(group, time=False)  # identify's --time-unit serves every log


def add_chain_arguments(group, unmeasured: bool = True) -> None:
    """--lock, --joints (the chain) and, for commands that read a log, --unmeasured."""
    group.add_argument("--lock", action="append", type=_lock, default=[],
                       metavar="JOINT[=POSITION]",
                       help="a URDF joint held out of the chain (e.g. gripper fingers) at "
                            "POSITION [rad, or m for a prismatic joint: a lift or a joint the "
                            "log holds still]; without one, at its logged position when the "
                            "log has a column named as the joint, else at 0; repeatable")
    group.add_argument("--joints", type=_joint_names, default=None, metavar="JOINT,...",
                       help="the chain's moving joints, from the root outward (the log's q1, "
                            "q2, ...): every other joint of the URDF is held, at its logged "
                            "position when the log has a column named as the joint, else at "
                            "0, so that a branching robot (a mobile base's wheels) reduces to "
                            "one arm")
    if not unmeasured:
        return
    group.add_argument("--unmeasured", type=_joint_names, default=None, metavar="JOINT,...",
                       help="URDF joints whose torque the log does not hold (no u column is "
                            "read for them): their equations are left out, their dynamics "
                            "stay in the other joints' equations")


def _lock(text: str) -> tuple[str, float | None]:
    """--lock JOINT (no position: logged or 0, harness.robot.held_joints) or
    JOINT=POSITION."""
    name, sign, value = text.partition("=")
    if not name.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: the joint name is empty")
    if not sign:
        return name.strip(), None
    try:
        return name.strip(), real(f"--lock {name.strip()}", value.strip())
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def locked_joints(locks: list[tuple[str, float | None]]) -> dict[str, float | None]:
    """The --lock options as joint -> position (None: none given); a joint locked twice is
    an error."""
    from .urdf import UrdfError
    names = [name for name, _ in locks]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise UrdfError(f"--lock names {', '.join(map(repr, twice))} more than once")
    return dict(locks)


def _joint_names(text: str) -> tuple[str, ...]:
    names = tuple(name.strip() for name in text.split(","))
    if not all(names):
        raise argparse.ArgumentTypeError(f"{text!r}: a joint name is empty")
    return names


def unmeasured_indices(names: tuple[str, ...] | None, robot) -> list[int]:
    """The 0-based joints --unmeasured names; UrdfError for a name the robot's chain lacks
    or a repeat, LogError for every joint."""
    from .joint_log import LogError
    from .urdf import joint_indices
    if names is None:
        return []
    text = ",".join(names)
    found = joint_indices(names, robot.joint_names, f"--unmeasured {text!r}")
    if len(found) == robot.n:
        raise LogError(f"--unmeasured {text!r}: no joint's torque would be left to identify "
                       "from")
    return sorted(found)


def add_unit_arguments(group, time: bool) -> None:
    """The options that give a robot log's units (harness.robot.log_units): --angle-unit,
    --length-unit, --torque-gains, and --time-unit when `time` (identify has its own,
    for every kind of log)."""
    if time:
        group.add_argument("--time-unit", choices=TIME_UNITS, default=None,
                           help="unit of the time column (default s)")
    group.add_argument("--angle-unit", choices=ANGLE_UNITS, default=None,
                       help="unit of the revolute joints' position columns (default rad)")
    group.add_argument("--length-unit", choices=LENGTH_UNITS, default=None,
                       help="unit of the prismatic joints' position columns (default m)")
    group.add_argument("--torque-gains", type=_gains, default=None, metavar="K1,K2,...",
                       help="the torque columns hold drive currents [A]: one gain per joint "
                            "[N.m/A, N/A for a prismatic joint], torque = gain x current "
                            "(default: the columns are torques [N.m, N])")


def _gains(text: str) -> tuple[float, ...]:
    """An argparse type: --torque-gains K1,K2,... (argparse names the option)."""
    from .log_units import UnitError, parse_gains
    try:
        return parse_gains(text)
    except UnitError as error:
        raise argparse.ArgumentTypeError(str(error).partition(": ")[2]) from None


def units_of(args, robot, held=()):
    """The LogUnits of the command's unit options for `robot` and the `held` joints' columns
    the log holds (HeldColumn; UnitError names a bad option)."""
    from .log_units import log_units
    return log_units([joint.kind for joint in robot.joints], time=args.time_unit,
                     angle=args.angle_unit, length=args.length_unit, gains=args.torque_gains,
                     held=[column.kind for column in held])


def _non_negative(text: str) -> float:
    """A finite number >= 0 (argparse names the option in its message)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f"{text!r} is not a number >= 0")
    return value


def _positive(name: str, high: float | None = None):
    """An argparse type: a finite number > 0 (and <= high)."""
    return argparse_type(real, name, low=0.0, low_open=True, high=high)


def _finite_non_negative(name: str):
    """An argparse type: a finite number >= 0."""
    return argparse_type(real, name, low=0.0)


def column_mapping(text: str, command: str) -> dict[str, str] | None:
    """--columns ROLE=COLUMN,... (roles t, q1..qn, u1..un; a column by name or 1-based
    number) as a mapping, or None after saying which item is malformed, which role is
    given twice or which column is given two roles."""
    from ..log_columns import LogColumnError, check_column_roles
    try:
        check_column_roles(text)
    except LogColumnError as error:
        print(f"harness {command}: {error}", file=sys.stderr)
        return None
    mapping = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        name, _, column = item.partition("=")
        if not column.strip():
            print(f"harness {command}: --columns item {item!r} is not ROLE=COLUMN",
                  file=sys.stderr)
            return None
        mapping[name.strip()] = column.strip()
    return mapping


def robot_and_log(args, mapping: dict[str, str]):
    """The robot of --robot (with --lock and --joints, its held joints at their logged
    positions where the log holds them) and its log in SI units (--columns mapped, the
    unit options applied): what identify and validate --robot both read first."""
    from .held_joints import held_without_position, hold_at_logged, logged_columns
    from .joint_log import LogError, read_log
    from .urdf import read_urdf
    if args.sample_rate is not None and args.time_unit is not None:
        raise LogError("--sample-rate and --time-unit: with a sample rate no time column is "
                       "read; give one of the two")
    robot = read_urdf(args.robot, locked=locked_joints(args.lock), joints_used=args.joints)
    roles = ["t", *(f"q{i}" for i in range(1, robot.n + 1)),
             *(f"u{i}" for i in range(1, robot.n + 1))]
    unmeasured = unmeasured_indices(args.unmeasured, robot)
    roles = [role for role in roles if role not in {f"u{i + 1}" for i in unmeasured}]
    unknown = [role for role in mapping if role not in roles and role not in robot.locked]
    if unknown:  # a role of another robot (or an unmeasured torque) would be left unread
        still = held_without_position(robot)
        raise LogError(f"--columns names {', '.join(map(repr, unknown))}, which "
                       f"{'is' if len(unknown) == 1 else 'are'} not a role of this "
                       f"{robot.n}-joint robot (roles: {', '.join(roles)}"
                       f"{'; --unmeasured leaves out the others' if unmeasured else ''}"
                       f"{'; held joints: ' + ', '.join(still) if still else ''})")
    held = logged_columns(args.data, robot, mapping, roles)
    log = read_log(args.data, robot.n, mapping, units=units_of(args, robot, held),
                   sample_rate=args.sample_rate, unmeasured=unmeasured, held=held)
    return hold_at_logged(robot, log, args.joints, args.data), log


def identify_command(args) -> int:
    from ..outputs import Outputs, shown
    from .consistency import ProjectionError
    from .held_joints import logged_lines
    from .joint_log import LogError
    from .joint_terms import JointTermsError, parse_terms
    from .layout import ParameterLayout
    from .log_units import UnitError
    from .pipeline import identify_robot
    from .results import OUTPUT_NAMES, write_results
    from .urdf import UrdfError
    mapping = column_mapping(args.columns, "identify")
    if mapping is None:
        return 2
    # auto unless the terms are named (none: the core's model alone) or --smooth-coulomb
    # gives the symmetric Coulomb friction its own shape
    named = (args.joint_terms or "").strip()
    auto = named == "auto" or (not named and args.smooth_coulomb is None)
    try:
        if auto and args.smooth_coulomb is not None:
            raise JointTermsError("--joint-terms auto chooses among offset, armature and "
                                  "asymmetric-coulomb; --smooth-coulomb cannot join that "
                                  "choice: name the terms instead")
        terms = None if auto else parse_terms(args.joint_terms, args.smooth_coulomb)
    except JointTermsError as error:
        print(f"harness identify: {error}", file=sys.stderr)
        return 2
    try:
        with Outputs(args.out, "identify", inputs=[args.data, args.robot],
                     names=OUTPUT_NAMES) as outputs:
            robot, log = robot_and_log(args, mapping)
            speed = {} if args.min_speed is None else {"min_speed": args.min_speed}
            if args.urdf_tolerance is not None:
                speed["urdf_tolerance"] = args.urdf_tolerance
            bounds = mass_bounds(robot, args.mass_range, args.total_mass,
                                 args.com_in_geometry)
            choose = ("required" if named == "auto" else "default") if auto else None
            result = identify_robot(robot, log, unknown=args.unknown, method=args.velocity,
                                    window=args.window, terms=terms, choose_terms=choose,
                                    mass_bounds=bounds, **speed)
            # the name goes into identified.urdf's comment: one line of printable text
            written = write_results(outputs.staging, robot, log, result,
                                    plain(Path(args.data).name))
    except (UrdfError, LogError, UnitError, ProjectionError) as error:
        print(f"harness identify: {error}", file=sys.stderr)
        return 2
    print(f"wrote {shown(*(outputs.final(path) for path in written))}")
    if log.resampled:
        print(f"  {args.data}: {log.resampled}")
    for line in logged_lines(robot, log):
        print(f"  {line}")
    if args.window is None:
        print(f"  regression window {result.window:.3g} s (the joints' longest velocity "
              f"window, at least 0.05 s; --window sets it)")
    n, terms = robot.n, result.terms
    if result.terms_choice is not None:
        _print_terms_choice(result.terms_choice)
    standard, layout = result.standard(n), ParameterLayout(n)
    values = result.term_values(n)
    for i, joint in enumerate(robot.joints):
        coulomb = ("" if terms.asymmetric_coulomb else
                   f", Coulomb {standard[layout.coulomb(i)]:.6g}")
        extras = "".join(f", {kind} {values[i, j]:.6g}" for j, kind in enumerate(terms.kinds))
        print(f"  {joint.name}: mass {standard[layout.mass(i)]:.6g} kg, viscous "
              f"{standard[layout.viscous(i)]:.6g}{coulomb}{extras}")
    if terms.any and result.urdf_kept:
        print("  the joint terms are not written: identified.urdf keeps the URDF's values")
    elif terms.any:
        mean = (" (identified.urdf holds the mean of the two Coulomb levels)"
                if terms.asymmetric_coulomb else "")
        print(f"  the joint terms: {outputs.final(written[-1])}{mean}")
    _print_assessment(result)
    if args.com_in_geometry:
        _print_com_boxes(robot, bounds)
    return 0


def _print_com_boxes(robot, bounds) -> None:
    """--com-in-geometry: which centres of mass the shapes bound, which they cannot."""
    named = [robot.joints[i].child_link for i in bounds.com_boxes]
    print(f"  centres of mass held inside their shapes' box: {', '.join(named) or 'none'}")
    for link, why in bounds.without_box.items():
        print(f"  {link}: no box for its centre of mass ({why})")
    outside = bounds.urdf_outside(robot)
    if outside:
        print(f"  the URDF's own centre of mass lies outside its shapes' box: "
              f"{', '.join(outside)} (its <inertial> and its shapes disagree)")


def _print_terms_choice(choice) -> None:
    """--joint-terms auto: every class's cross-validated error and the one kept."""
    from .model_class import ABSENCE_REPORTED, BLOCKS, label
    if choice.note is not None:
        print(f"  joint terms: {choice.note}")
        return
    print(f"  joint terms by cross-validation (held-out torque error, mean of {BLOCKS} "
          "blocks):")
    for name, score in choice.scores.items():
        mark = "  <- chosen" if name == label(choice.terms) else ""
        shown = f"{100 * score:.3f} %" if score is not None else choice.reasons.get(
            name, "could not be fitted")
        print(f"    {name:<36} {shown}{mark}")
    for item, cost in choice.absence_costs().items():
        if cost > ABSENCE_REPORTED:
            print(f"  without {item} the class kept scores {100 * cost:.1f} % worse: this "
                  "log needs it")


def _print_assessment(result) -> None:
    """The training-log prediction errors, the consistent projection's objective, the
    passive joints and the warnings."""
    if result.choice is not None:
        scores = ", ".join(f"{name} {100 * p.pooled:.3f} %"
                           for name, p in result.choice.predictions.items())
        print(f"  training-log torque prediction error (pooled): {scores}; identified.urdf "
              f"holds the {result.choice.written} model")
    if result.projection is not None:
        p = result.projection
        print(f"  consistent projection ({p.status}): Mahalanobis distance^2 {p.distance:.4g} "
              f"(95 % bound {p.bound:.4g}), URDF prior {p.divergence:.4g}, friction and "
              f"joint terms prior {p.terms_prior:.4g} at --urdf-tolerance {p.tolerance:g}")
    for name in result.passive:
        print(f"  {name}: torque 0 throughout, taken as a passive joint (its equation, "
              f"torque = 0, constrains the parameters)")
    for name in result.unmeasured:
        print(f"  {name}: torque not measured (--unmeasured): its equation is left out; what "
              "only it holds (its friction) keeps the URDF's values, standard error 0")
    for message in result.warnings:  # counted: the command exits 1 (docs/cli.md)
        note(message)


def register_fmu_parameters(sub, parents) -> None:
    """The robot-fmu-parameters command."""
    p = sub.add_parser("robot-fmu-parameters", parents=parents,
                       help="the RobotObserver FMU's parameters from a URDF (SSP parameter set)",
                       description="Writes the robot's kinematic and inertial data, the base "
                       "columns of its regressor and the nominal base parameters as an SSP "
                       "parameter set (SSV) with the FMU's FMI 2 variable names.")
    p.add_argument("urdf", help="the robot's URDF")
    p.add_argument("--out", required=True, metavar="FILE", help="the .ssv file to write")
    add_chain_arguments(p, unmeasured=False)
    p.add_argument("--unknown", choices=["all", "payload"], default="all",
                   help="identified: every base parameter and the friction (all), or the "
                        "last link's parameters and the friction (payload)")
    p.add_argument("--identifier", choices=["off", "lsm", "mff"], default="lsm",
                   help="the FMU's base-parameter identifier: off, least squares (lsm, "
                        "default) or matrix forgetting factor (mff)")
    p.add_argument("--step", type=_positive("--step", high=1.0), default=1e-3,
                   help="sampling period h [s] (0 < h <= 1, the FMU's range)")
    p.add_argument("--f-plus", type=_positive("--f-plus"), default=10.0,
                   help="bound on the model's acceleration error [rad/s^2] (every joint, > 0)")
    p.add_argument("--coulomb-velocity", type=_finite_non_negative("--coulomb-velocity"),
                   default=0.0,
                   help="Coulomb friction saturates below this velocity [rad/s] (0: sign)")
    p.add_argument("--min-speed", type=_non_negative, default=None, metavar="V",
                   help="the identifier leaves out joint equations at |q'| < V [rad/s or "
                        "m/s] and at reversals, where Coulomb friction is not f_c sign(q') "
                        "(default 0.05)")
    p.add_argument("--reversal-margin", type=_non_negative, default=None, metavar="S",
                   help="... and for S seconds after (default 0.02; with --min-speed 0, "
                        "0 uses every equation)")
    p.set_defaults(func=fmu_parameters_command)


def fmu_parameters_command(args) -> int:
    from ..outputs import Outputs, shown
    from .fmu import fmu_parameters, write_ssv
    from .urdf import UrdfError, read_urdf
    target = Path(args.out)
    outputs = Outputs(target.parent, "robot-fmu-parameters", inputs=[args.urdf],
                      names=[target.name], lock=False)  # one file: its rename is atomic
    try:
        robot = read_urdf(args.urdf, locked=locked_joints(args.lock), joints_used=args.joints)
        rule = {name: value for name, value in (("min_speed", args.min_speed),
                                                ("reversal_margin", args.reversal_margin))
                if value is not None}
        parameters = fmu_parameters(robot, unknown=args.unknown, h=args.step,
                                    f_plus=args.f_plus, identifier=args.identifier,
                                    coulomb_velocity=args.coulomb_velocity, **rule)
    except (UrdfError, ValueError) as error:
        print(f"harness robot-fmu-parameters: {error}", file=sys.stderr)
        return 2
    with outputs:
        write_ssv(parameters, outputs.file(target.name), name=Path(args.urdf).stem)
    print(f"wrote {shown(target)}: {robot.n} joints, {parameters['base_count']} base parameters")
    # written, but the FMU models less than the identified robot: exit 1 (docs/cli.md)
    return 1 if _warn_unused_joint_terms(args.urdf, robot.joint_names) else 0


def _warn_unused_joint_terms(urdf: str, joint_names: list[str]) -> bool:
    """The RobotObserver FMU carries the URDF's model only: say so when an identify run's
    joint_terms.csv with terms sits beside the URDF (they are not in the parameters);
    True when it did."""
    from .joint_terms import SIDECAR_NAME, JointTermsError, read_sidecar
    beside = Path(urdf).parent / SIDECAR_NAME
    if not beside.is_file():
        return False
    try:
        terms = read_sidecar(beside, joint_names).terms
    except JointTermsError:
        return False  # not this robot's terms
    if terms.any:
        kinds = [*terms.kinds] + (["smooth Coulomb"] if terms.smooth_coulomb else [])
        print(f"harness robot-fmu-parameters: warning: {beside} holds joint terms "
              f"({', '.join(kinds)}) that the RobotObserver FMU does not model: its "
              "parameters are the URDF's model alone", file=sys.stderr)
    return terms.any
