"""Command line: ``sto-harness`` (or ``python -m harness``).

    reproduce [--scenario NAME|all] --out DIR   the paper's section 6 examples
    identify DATA.csv --out DIR [--columns t=time,y=theta,u=tau] [--param NAME=VALUE ...]
                                                offline identification of a recorded log
    identify DATA.csv --robot ROBOT.urdf --out DIR   a serial robot (harness.robot)
    identify LOG --model MODEL.toml --out DIR   a model file's unknowns (CSV, Parquet, .mat log)
    validate LOG --model MODEL.toml --out DIR   a model file's input reconstruction error
    fmu --model MODEL.toml --out DIR            a model file's observer/identifier FMU
    validate LOG --robot ROBOT.urdf --out DIR   a URDF's torque prediction error (harness.robot)
    robot-fmu-parameters ROBOT.urdf --out FILE.ssv   the RobotObserver FMU's parameters
    demo [--out DIR]                            the closed-loop demonstration (reproduce + compare)
    compare --out DIR                           paper method vs the improved defaults
    sweep SPEC --out DIR [--scheduler tcp://HOST:PORT]   parameter / noise sweeps on Dask

Options of every command (before or after it): --fmu-dir DIR, --quiet.
Exit status: 0 done; 1 done, but the result cannot be trusted (an FMU warned, the
observer did not converge, some sweep runs failed: see stderr); 2 bad input (named in
the message), an FMU error, or the outputs could not be written (then none was: every
command writes its files under a temporary name and renames them when all are
complete, harness.outputs); 3 a sweep's --out is locked by another sweep; 130
interrupted (Ctrl-C), 143 terminated (SIGTERM): nothing of the run is written.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Mapping
from pathlib import Path

from .blas_threads import one_blas_thread
from .fmus import FMUError
from .inputs import InputError
from .json_files import write_json
from .messages import Console
from .outputs import OutputError, Outputs, Terminated, shown
from .paths import default_fmu_dir
from .units import TIME_UNITS
from .values import INT32_MAX, BadValue, argparse_type, integer, real


def _fmu_dir(args) -> Path:
    path = Path(args.fmu_dir) if args.fmu_dir else default_fmu_dir()
    if not (path / "SuperTwistingObserver.fmu").exists():
        raise InputError(f"harness: no FMUs in {path}: run ./build.sh fmus first "
                         f"(or pass --fmu-dir)")
    return path


def _format(value: float) -> str:
    return f"{value:.3g}" if isinstance(value, float) else str(value)


def cmd_reproduce(args) -> int:
    from .master import Progress
    from .metrics import score
    from .plots import plot_scenario
    from .scenarios import SCENARIOS, all_choices, run_scenario

    names = list(SCENARIOS) if args.scenario == "all" else [args.scenario]
    fmu_dir = _fmu_dir(args)
    summary = {}
    with Outputs(args.out, "reproduce", inputs=_fmu_files(fmu_dir),
                 names=[f"{n}/{f}" for n in names for f in ("signals.csv", "metrics.json")]
                 ) as outputs:
        for name in names:
            scenario = SCENARIOS[name]
            print(f"{name}: {scenario.title} ({scenario.stop_time:g} s)", flush=True)
            records = run_scenario(scenario, fmu_dir, noise_std=args.noise, seed=args.seed,
                                   use_native=False if args.python_loop else None,
                                   progress=Progress(name, quiet=True if args.quiet else None))
            metrics = score(scenario, records)
            decimation = args.csv_decimation
            from .master import Records
            Records(records.time[::decimation],
                    {k: v[::decimation] for k, v in records.signals.items()}).to_csv(
                outputs.file(f"{name}/signals.csv"))
            # a metric never reached (a settling time) is inf: null in JSON
            write_json(outputs.file(f"{name}/metrics.json"),
                       {"scenario": name, "title": scenario.title, "noise_std": args.noise,
                        "metrics": metrics, "choices": all_choices(scenario)}, warn=False)
            plot_scenario(scenario, records, outputs.staging / name)
            summary[name] = metrics
    for path in outputs.written:
        if path.suffix == ".png":
            print(f"  wrote {shown(path)}")
    print()
    print(summary_table(summary))
    return 0


def summary_table(summary: dict[str, dict[str, float]]) -> str:
    headline = {
        "perturbation": ["rms_perturbation", "delay"],
        "lsm": ["a1_rel_error_end", "a2_rel_error_end", "a3_rel_error_end"],
        "mff": ["rms_damping", "damping_lag"],
    }
    from .scenarios import SCENARIOS

    lines = [f"{'scenario':<11} {'conv. [s]':>9} {'max|e2| [rad/s]':>15}  identification"]
    for name, m in summary.items():
        keys = headline[SCENARIOS[name].kind]
        ident = ", ".join(f"{k} = {_format(m[k])}" for k in keys)
        lines.append(f"{name:<11} {m['convergence_time']:>9.3f} "
                     f"{m['max_e2_after_1s']:>15.2e}  {ident}")
    return "\n".join(lines)


def _parse_params(items: list[str]) -> dict[str, int | float | bool]:
    """NAME=VALUE items: true/false, an integer, or a number (typed and range-checked
    against the FMU by fmus.check_parameters)."""
    params: dict[str, int | float | bool] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise InputError(f"harness: --param {item!r}: expected NAME=VALUE")
        lowered = text.strip().lower()
        if lowered in ("true", "false"):
            params[name.strip()] = lowered == "true"
            continue
        try:
            params[name.strip()] = int(text)
        except ValueError:
            try:
                params[name.strip()] = float(text)
            except ValueError:
                raise InputError(f"harness: --param {item!r}: {text!r} is not a number") from None
    return params


def _fmu_files(fmu_dir: Path) -> list[Path]:
    """The FMUs a command reads (outputs never overwrite them)."""
    return sorted(fmu_dir.glob("*.fmu"))


# identify's options for a recorded log of t, y, u, and their defaults: the robot and
# model-file paths read their logs themselves and refuse them rather than ignoring them
# (the robot path takes --time-unit)
LOG_OPTIONS = {"identifier": ("--identifier", "lsm"), "param": ("--param", []),
               "time_unit": ("--time-unit", None), "time_tolerance": ("--time-tolerance", 0.01),
               "resample": ("--resample", None), "input_hold": ("--input-hold", "zoh"),
               "csv_decimation": ("--csv-decimation", 1), "format": ("--format", "csv")}
# the options of the robot path (harness.robot.cli), refused without --robot
ROBOT_OPTIONS: dict[str, tuple[str, object]] = {
    "lock": ("--lock", []), "joints": ("--joints", None), "unmeasured": ("--unmeasured", None),
    "unknown": ("--unknown", "all"), "velocity": ("--velocity", "sg"),
    "window": ("--window", None), "min_speed": ("--min-speed", None),
    "angle_unit": ("--angle-unit", None), "length_unit": ("--length-unit", None),
    "torque_gains": ("--torque-gains", None), "joint_terms": ("--joint-terms", None),
    "mass_range": ("--mass-range", []), "total_mass": ("--total-mass", None),
    "com_in_geometry": ("--com-in-geometry", False),
    "smooth_coulomb": ("--smooth-coulomb", None)}
# the options of the model-file path (harness.model.cli), refused without --model
MODEL_OPTIONS = {"refine": ("--refine", "auto")}
# the options of the model-file and robot paths (one log reader), refused without either
SIGNAL_OPTIONS = {"sample_rate": ("--sample-rate", None)}


def _given(args, options: Mapping[str, tuple[str, object]]) -> list[str]:
    """The options of `options` given a value other than their default."""
    return [option for dest, (option, default) in options.items()
            if getattr(args, dest) != default]


def _refuse(given: list[str], path: str, why: str) -> None:
    if given:
        raise InputError(f"harness identify: {', '.join(given)} not available with {path} "
                         f"({why}); leave {'them' if len(given) > 1 else 'it'} out")


def cmd_identify(args) -> int:
    if args.urdf_tolerance is not None and not args.robot:
        raise InputError("harness identify: --urdf-tolerance is the URDF's prior: it needs "
                         "--robot")
    if not args.model:
        _refuse(_given(args, MODEL_OPTIONS), "this log", "it refines a model file's "
                "parameters: it needs --model")
    if not (args.model or args.robot):
        _refuse(_given(args, SIGNAL_OPTIONS), "a t, y, u log", "it states the sample rate of "
                "a log read with --model or --robot; --resample evens a t, y, u log's clock")
    if args.model:  # a model file: harness.model.cli
        given = _given(args, LOG_OPTIONS) + _given(args, ROBOT_OPTIONS)
        given += ["--robot"] if args.robot else []
        given += ["--columns"] if args.columns else []
        _refuse(given, "--model", "the model file's [columns] maps the log, its [units] "
                "gives the columns' units, t = \"ms\" the time's")
        from .model.cli import identify_command as identify_model
        return identify_model(args)
    if args.robot:  # a serial robot from its URDF: harness.robot
        from .robot.cli import identify_command
        given = [option for option in _given(args, LOG_OPTIONS) if option != "--time-unit"]
        _refuse(given, "--robot", "the robot log is read as t, q1..qn, u1..un, evenly "
                "sampled; --time-unit, --angle-unit, --length-unit and --torque-gains give "
                "its units")
        return identify_command(args)
    _refuse(_given(args, ROBOT_OPTIONS), "a t, y, u log", "they go with --robot")
    from .fmus import check_parameters
    from .identify import DataError, ReadOptions, identify_file
    from .log_columns import LogColumnError, check_column_roles
    from .recording import parse_columns

    fmu = _fmu_dir(args) / "SuperTwistingObserver.fmu"
    parameters = check_parameters(fmu, {
        "identifier": {"off": 0, "lsm": 1, "mff": 2}[args.identifier],
        **_parse_params(args.param)})
    try:
        columns = parse_columns(args.columns)
        check_column_roles(args.columns, fold_case=True)  # names are looked up without case
        options = ReadOptions(columns=columns, time_unit=args.time_unit,
                              tolerance=args.time_tolerance,
                              resample=None if args.resample is None else args.resample)
    except (DataError, LogColumnError) as error:
        print(f"harness identify: {error}", file=sys.stderr)
        return 2
    table_name = f"estimates.{args.format}"
    try:
        with Outputs(args.out, "identify", inputs=[args.data, fmu],
                     names=[table_name, "estimates.json", "identification.png"]) as outputs:
            summary = identify_file(args.data, fmu, parameters, outputs.file(table_name),
                                    options=options, input_hold=args.input_hold,
                                    decimation=args.csv_decimation)
            from .plots import plot_identification  # matplotlib: once the log is through

            plot = outputs.final(plot_identification(
                summary.figure_rows["t"], summary.figure_rows, outputs.staging,
                nominal=_nominal(fmu, parameters)))
            write_json(outputs.file("estimates.json"),
                       {**summary.as_json(), "parameters": parameters,
                        "input_hold": args.input_hold, "columns": options.columns,
                        "time_unit": args.time_unit, "resample": args.resample})
    except DataError as error:
        print(f"harness identify: {error}", file=sys.stderr)
        return 2
    if summary.h != summary.step:
        print(f"note: samples {summary.step:g} s apart are more than the observer's largest "
              f"internal step: h = {summary.h:g} s ({round(summary.step / summary.h)} internal "
              f"steps per sample); set it with --param h=...")
    out = outputs.folder
    print(f"wrote {shown(out / table_name, out / 'estimates.json', plot)}")
    for name, value in summary.final.items():
        print(f"  {name} = {value:.6g} +- {summary.standard_error[name]:.2g} (1 sigma)")
    print(f"  measurement noise (estimated) = {summary.noise_std:.3g} rad")
    print(f"  observer converged: {'yes' if summary.converged else 'no'}; identifier active: "
          f"{'yes' if summary.identifier_active else 'no'}; excitation = "
          f"{summary.excitation:.3g}")
    if not summary.converged:
        print("harness identify: the observer has not converged by the end of the record: "
              "the estimates cannot be trusted (check the gains, b and the nominal model)",
              file=sys.stderr)
        return 1
    return 0


def _nominal(fmu: Path, parameters: dict) -> dict[str, float]:
    """The nominal coefficients and b the observer ran with (given or the FMU's start)."""
    from fmpy import read_model_description

    names = [f"c_nominal[{k}]" for k in range(1, 6)] + ["b"]
    start = {v.name: v.start for v in read_model_description(str(fmu)).modelVariables
             if v.name in names}
    return {n: float(parameters.get(n, start.get(n) or 0.0)) for n in names}


def cmd_demo(args) -> int:
    """The paper's examples with the paper's method, then the improved defaults beside it."""
    out = Path(args.out)
    args.scenario, args.noise, args.seed, args.csv_decimation = "all", 0.0, 0, 10
    args.python_loop = False
    cmd_reproduce(args)
    print("\npaper method vs the FMU's defaults (noise-free):")
    args.out, args.noise = str(out / "compare"), (0.0,)
    return cmd_compare(args)


def cmd_compare(args) -> int:
    from .compare import markdown_table, run_comparison

    noise = args.noise if isinstance(args.noise, tuple) else _noise_list(args.noise)
    fmu_dir = _fmu_dir(args)
    with Outputs(args.out, "compare", inputs=_fmu_files(fmu_dir),
                 names=["compare.csv", "compare.json", "compare.md"]) as outputs:
        rows = run_comparison(fmu_dir, outputs.staging,
                              None if args.scenario == "all" else [args.scenario], noise,
                              quiet=True if args.quiet else None)
    print(markdown_table(rows))
    print(f"\nwrote {shown(Path(args.out) / 'compare.md')}, compare.csv and figures")
    return 0


def _noise_list(text: str) -> tuple[float, ...]:
    """compare --noise: comma-separated noise levels, each finite and >= 0."""
    try:
        levels = tuple(real("--noise", item, 0.0) for item in text.split(","))
    except BadValue as error:
        raise argparse.ArgumentTypeError(f"{error} (give comma-separated standard deviations "
                                         f">= 0, e.g. 0,1e-5,1e-4)") from None
    return levels


NOISE = argparse_type(real, "--noise", low=0.0)
SEED = argparse_type(integer, "--seed", low=0, high=2**63 - 1)
DECIMATION = argparse_type(integer, "--csv-decimation", low=1, high=INT32_MAX)
TOLERANCE = argparse_type(real, "--time-tolerance", low=0.0)
RESAMPLE = argparse_type(real, "--resample", low=0.0)
SAMPLE_RATE = argparse_type(real, "--sample-rate", low=0.0, low_open=True)


def global_options() -> argparse.ArgumentParser:
    """Options every command takes, before or after its name (a parent parser: the
    subcommands leave them alone when not given, argparse.SUPPRESS)."""
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--fmu-dir", default=argparse.SUPPRESS, metavar="DIR",
                        help="folder of the FMUs (default: $STO_FMU_DIR, else build/fmus "
                             "of a source checkout, else the FMUs installed with the package)")
    common.add_argument("--quiet", "-q", action="store_true", default=argparse.SUPPRESS,
                        help="no progress bars and no warnings on stderr, only errors (the "
                             "exit status still says when a result cannot be trusted)")
    return common


def build_parser() -> argparse.ArgumentParser:
    from .robot.cli import register_fmu_parameters
    from .sweep import register as register_sweep

    common = global_options()
    parser = argparse.ArgumentParser(prog="sto-harness", description=__doc__, parents=[common],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for register in (register_paper_commands, register_identify, register_fmu_parameters,
                     register_sweep, register_validate, register_fmu):
        register(sub, parents=[common])
    return parser


def register_paper_commands(sub, parents) -> None:
    """reproduce, demo and compare: the paper's section 6 in closed loop."""
    from .scenarios import SCENARIOS
    scenario_help = "a scenario of the paper's section 6, or all (default)"

    p = sub.add_parser("reproduce", parents=parents, help="run the paper's section 6 examples",
                       description="Runs the paper's section 6 examples in closed loop and "
                       "writes signals.csv, metrics.json and figures per scenario.")
    p.add_argument("--scenario", default="all", choices=["all", *SCENARIOS], help=scenario_help)
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument("--noise", type=NOISE, default=0.0, help="std of noise on theta [rad], >= 0")
    p.add_argument("--seed", type=SEED, default=0, help="noise seed, >= 0")
    p.add_argument("--csv-decimation", type=DECIMATION, default=10, metavar="N",
                   help="write every Nth step to signals.csv (default 10, >= 1)")
    p.add_argument("--python-loop", action="store_true", help="use the plain-Python master loop")
    p.set_defaults(func=cmd_reproduce)

    p = sub.add_parser("demo", parents=parents, help="the closed-loop demonstration: all "
                       "scenarios, paper method and improved defaults")
    p.add_argument("--out", default="demo", metavar="DIR",
                   help="output folder (default: ./demo)")
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser("compare", parents=parents,
                       help="paper method vs the improved defaults, with noise")
    p.add_argument("--scenario", default="all", choices=["all", *SCENARIOS], help=scenario_help)
    p.add_argument("--noise", type=_noise_list, default=(0.0, 1e-5, 1e-4),
                   help="comma-separated noise std [rad], each >= 0 (default 0,1e-5,1e-4)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.set_defaults(func=cmd_compare)


def register_identify(sub, parents) -> None:
    """identify: a log through the observer FMU, a model file (--model) or a robot (--robot)."""
    p = sub.add_parser("identify", parents=parents,
                       help="identify from a recorded log (CSV, Parquet)",
                       description="Feeds a recorded experiment through the observer FMU and "
                       "writes estimates.csv, estimates.json and identification.png.")
    p.add_argument("data", help="the log: CSV (.csv, .txt) with a header row naming the time, "
                   "position and input columns, or Parquet (.parquet, .pq); with --model "
                   "also MATLAB (.mat). The format is told by the extension")
    p.add_argument("--model", metavar="MODEL.toml",
                   help="a model file (docs/model_files.md): identify its unknowns from the "
                        "log; writes parameters.csv, identified.toml, estimates.csv and a plot")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument("--identifier", choices=["off", "lsm", "mff"],
                   default=LOG_OPTIONS["identifier"][1],
                   help="least squares for constant parameters (lsm, default), with matrix "
                        "forgetting factor for time-varying ones (mff), or none")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="observer FMU parameter, e.g. --param b=1.12 --param 'c_nominal[1]=2'")
    p.add_argument("--columns", default="", metavar="t=NAME,y=NAME,u=NAME",
                   help="the file's names of the time, position and input columns (default: "
                        "t or time, y, u; any case), e.g. t=time,y=theta,u=tau; with --robot "
                        "the roles are t, q1..qn, u1..un, e.g. q1=shoulder_pos")
    p.add_argument("--time-unit", default=LOG_OPTIONS["time_unit"][1], choices=TIME_UNITS,
                   help="unit of the time column (default: seconds, with a warning when whole-"
                        "number stamps 1 or more apart look like milliseconds); epoch time "
                        "stamps are fine; also with --robot (with --model: [units] t)")
    p.add_argument("--time-tolerance", type=TOLERANCE, default=LOG_OPTIONS["time_tolerance"][1],
                   metavar="FRACTION",
                   help="how far a sampling step may differ from the recording's step, as a "
                        "fraction of it (default 0.01: clock jitter); larger gaps are refused "
                        "unless --resample")
    p.add_argument("--resample", type=RESAMPLE, default=LOG_OPTIONS["resample"][1], nargs="?",
                   const=0.0,
                   metavar="STEP",
                   help="put the samples on a uniform grid of STEP seconds first (without "
                        "STEP: the median step): y interpolated linearly, u holds its last "
                        "value; the time stamps written are then the grid's")
    p.add_argument("--input-hold", choices=["zoh", "sampled"],
                   default=LOG_OPTIONS["input_hold"][1],
                   help="zoh: u[k] was applied over the interval after t_k (a controller's "
                        "command, the default); sampled: u[k] samples a continuous signal")
    p.add_argument("--csv-decimation", type=DECIMATION, metavar="N",
                   default=LOG_OPTIONS["csv_decimation"][1],
                   help="write every Nth sample to the estimates table (default 1: all)")
    p.add_argument("--format", choices=["csv", "parquet"], default=LOG_OPTIONS["format"][1],
                   help="the written table: estimates.csv (default) or estimates.parquet "
                        "(faster for long logs); the log's own format is told by its "
                        "extension")
    p.add_argument("--refine", choices=["auto", "simulation", "none"],
                   default=MODEL_OPTIONS["refine"][1],
                   help="with --model: refine the least-squares estimate by output error "
                        "(the model simulated from the measured input follows the measured "
                        "positions): simulation always, none never, auto (default) when it "
                        "improves the simulation error on held-out halves of the log")
    p.add_argument("--sample-rate", type=SAMPLE_RATE, default=SIGNAL_OPTIONS["sample_rate"][1],
                   metavar="HZ",
                   help="with --model or --robot: the log's samples are evenly spaced at HZ "
                        "samples per second from t = 0, and no time column is read (a .mat "
                        "log without a time vector; a model file's [log] sample_rate says the "
                        "same)")
    from .robot.cli import add_arguments as add_robot_arguments
    add_robot_arguments(p)
    p.set_defaults(func=cmd_identify)


# The validate command: its model-file and robot paths import what they run when run
# (the model files' sympy and pint, the robots' scipy.signal), not when the parser is built.
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


def register_fmu(sub, parents) -> None:
    """The fmu command's parser."""
    p = sub.add_parser("fmu", parents=parents,
                       help="the observer/identifier FMU of a model file",
                       description="Writes DIR/<model>.fmu: the super-twisting observer and "
                       "LSM/MFF identifier of the model file's equations (read by the FMU "
                       "from its resources; no compiler needed), with the model's coordinates "
                       "and inputs as inputs, der(c) and each unknown (with <name>_std) as "
                       "outputs (docs/model_files.md, 'The FMU').")
    p.add_argument("--model", required=True, metavar="MODEL.toml", help="the model file")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument("--fmi-version", type=int, choices=(2, 3), default=2,
                   help="FMI 2.0 or 3.0 (default 2)")
    p.add_argument("--identifier", choices=("lsm", "mff"), default=None,
                   help="lsm: least squares, constant parameters (the default); mff: matrix "
                        "forgetting factor, time-varying parameters")
    p.set_defaults(func=_fmu)


def _fmu(args: argparse.Namespace) -> int:
    from .model.fmu_export import fmu_command  # sympy and lxml: loaded for this command only
    return fmu_command(args)


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
    from .model.cli import validate_command
    return validate_command(args)


def main(argv: list[str] | None = None) -> int:
    """Runs the command line; returns the exit status (see the module documentation)."""
    try:
        with one_blas_thread():
            return _main(argv)
    except KeyboardInterrupt as interrupt:  # Ctrl-C outside a command (parsing, the console)
        print("\nharness: interrupted", file=sys.stderr)
        return 143 if isinstance(interrupt, Terminated) else 130


def _main(argv: list[str] | None) -> int:
    args = build_parser().parse_args(argv)
    args.fmu_dir = getattr(args, "fmu_dir", None)
    args.quiet = getattr(args, "quiet", False)
    with Console(quiet=args.quiet) as console:
        try:
            code = args.func(args)
        except (FMUError, InputError, OutputError) as error:
            print(error if str(error).startswith("harness") else f"harness: {error}",
                  file=sys.stderr)
            return 2
        except BrokenPipeError:
            _silence_stdout()  # the reader went away (| head): nothing more to say
            return 0
        except OSError as error:  # a full or read-only disk, a vanished file: nothing written
            where = f" {error.filename}:" if error.filename else ""
            print(f"harness:{where} {error.strerror or error}", file=sys.stderr)
            return 2
        except KeyError as error:
            print(f"harness: {error.args[0] if error.args else error}", file=sys.stderr)
            return 2
        except KeyboardInterrupt as interrupt:  # Ctrl-C or SIGTERM (outputs.Terminated)
            print("\nharness: interrupted", file=sys.stderr)
            return 143 if isinstance(interrupt, Terminated) else 130
        if code == 0 and console.warnings + console.errors:
            print(f"harness: the FMUs or the harness warned {console.warnings + console.errors} "
                  f"time(s) (see above{'; --quiet hid them' if args.quiet else ''}): the "
                  f"results cannot be trusted as they are", file=sys.stderr)
            return 1
        return code


def _silence_stdout() -> None:
    """Points stdout at /dev/null, so that Python's final flush does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # not a real file (tests): nothing to redirect
        pass


if __name__ == "__main__":
    sys.exit(main())
