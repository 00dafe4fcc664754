"""Command line: ``python -m harness`` (or ``sto-harness``).

    reproduce [--scenario NAME|all] --out DIR   the paper's section 6 examples
    identify DATA.csv --out DIR [--param NAME=VALUE ...]   offline identification
    identify DATA.csv --robot ROBOT.urdf --out DIR         a serial robot (harness.robot)
    demo [--out DIR]                            the closed-loop demonstration (reproduce + compare)
    compare --out DIR                           paper method vs the improved defaults
    sweep SPEC --out DIR [--scheduler tcp://HOST:PORT]   parameter / noise sweeps on Dask
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .fmus import FMUError
from .values import INT32_MAX, BadValue, argparse_type, integer, real

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FMU_DIR = REPO / "build" / "fmus"


def _fmu_dir(args) -> Path:
    path = Path(args.fmu_dir)
    if not (path / "SuperTwistingObserver.fmu").exists():
        raise SystemExit(f"harness: no FMUs in {path}: run ./build.sh fmus first "
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
    out = _output_folder(args.out, "reproduce")
    summary = {}
    for name in names:
        scenario = SCENARIOS[name]
        print(f"{name}: {scenario.title} ({scenario.stop_time:g} s)")
        records = run_scenario(scenario, fmu_dir, noise_std=args.noise, seed=args.seed,
                               use_native=False if args.python_loop else None,
                               progress=Progress(name))
        metrics = score(scenario, records)
        folder = out / name
        folder.mkdir(parents=True, exist_ok=True)
        decimation = args.csv_decimation
        from .master import Records
        Records(records.time[::decimation],
                {k: v[::decimation] for k, v in records.signals.items()}).to_csv(
            folder / "signals.csv")
        (folder / "metrics.json").write_text(json.dumps(
            {"scenario": name, "title": scenario.title, "noise_std": args.noise,
             "metrics": metrics, "choices": all_choices(scenario)}, indent=2) + "\n")
        for path in plot_scenario(scenario, records, folder):
            print(f"  wrote {path}")
        summary[name] = metrics
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
        lines.append(f"{name:<11} {m['convergence_time']:>9.3f} {m['max_e2_after_1s']:>15.2e}  {ident}")
    return "\n".join(lines)


def _parse_params(items: list[str]) -> dict[str, int | float | bool]:
    """NAME=VALUE items: true/false, an integer, or a number (typed and range-checked
    against the FMU by fmus.check_parameters)."""
    params: dict[str, int | float | bool] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise SystemExit(f"harness: --param {item!r}: expected NAME=VALUE")
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
                raise SystemExit(f"harness: --param {item!r}: {text!r} is not a number") from None
    return params


def _output_folder(path: str, command: str) -> Path:
    """The --out folder, created now (before any computation): SystemExit with a
    message if it cannot be (a file of that name, no permission, ...)."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise SystemExit(f"harness {command}: --out {out} exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise SystemExit(f"harness {command}: cannot create --out {out}: "
                         f"{error.strerror or error}") from None
    return out


def cmd_identify(args) -> int:
    if args.robot:  # a serial robot from its URDF: harness.robot
        from .robot.cli import identify_command
        return identify_command(args, _output_folder(args.out, "identify"))
    from .fmus import check_parameters
    from .identify import (DataError, default_internal_step, final_estimates, identify,
                           largest_internal_step, read_recording, write_csv)
    from .plots import plot_identification

    fmu = _fmu_dir(args) / "SuperTwistingObserver.fmu"
    parameters = check_parameters(fmu, {
        "identifier": {"off": 0, "lsm": 1, "mff": 2}[args.identifier],
        **_parse_params(args.param)})
    out = _output_folder(args.out, "identify")
    try:
        recording = read_recording(args.data)
    except DataError as error:
        print(f"harness identify: {error}", file=sys.stderr)
        return 2
    h = parameters.get("h")
    if h is None:
        h_max = largest_internal_step(fmu)
        h = default_internal_step(recording.step, h_max)
        if h != recording.step:
            print(f"note: samples {recording.step:g} s apart are more than the observer's "
                  f"largest internal step ({h_max:g} s): h = {h:g} s "
                  f"({round(recording.step / h)} internal steps per sample); set it with "
                  f"--param h=...")
    columns = identify(recording, fmu, parameters, input_hold=args.input_hold)
    write_csv(columns, out / "estimates.csv")
    plot = plot_identification(columns["t"], columns, out)
    summary = final_estimates(columns)
    (out / "estimates.json").write_text(json.dumps({**summary, "parameters": parameters,
                                                    "h": h,
                                                    "input_hold": args.input_hold},
                                                   indent=2) + "\n")
    print(f"wrote {out / 'estimates.csv'}, {out / 'estimates.json'}, {plot}")
    for name, value in summary["final"].items():
        print(f"  {name} = {value:.6g} +- {summary['standard_error'][name]:.2g} (1 sigma)")
    print(f"  measurement noise (estimated) = {summary['noise_std']:.3g} rad")
    return 0


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
    rows = run_comparison(_fmu_dir(args), _output_folder(args.out, "compare"),
                          None if args.scenario == "all" else [args.scenario], noise)
    print(markdown_table(rows))
    print(f"\nwrote {Path(args.out) / 'compare.md'}, compare.csv and figures")
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


def main(argv: list[str] | None = None) -> int:
    from .scenarios import SCENARIOS

    parser = argparse.ArgumentParser(prog="python -m harness", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fmu-dir", default=str(DEFAULT_FMU_DIR),
                        help="folder with the built FMUs (default: build/fmus)")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("reproduce", help="run the paper's section 6 examples")
    p.add_argument("--scenario", default="all", choices=["all", *SCENARIOS])
    p.add_argument("--out", required=True)
    p.add_argument("--noise", type=NOISE, default=0.0, help="std of noise on theta [rad], >= 0")
    p.add_argument("--seed", type=SEED, default=0, help="noise seed, >= 0")
    p.add_argument("--csv-decimation", type=DECIMATION, default=10,
                   help="write every Nth step to signals.csv (default 10, >= 1)")
    p.add_argument("--python-loop", action="store_true", help="use the plain-Python master loop")
    p.set_defaults(func=cmd_reproduce)

    p = sub.add_parser("demo", help="the closed-loop demonstration: all scenarios, paper "
                       "method and improved defaults")
    p.add_argument("--out", default=str(REPO / "build" / "demo"))
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser("compare", help="paper method vs the improved defaults, with noise")
    p.add_argument("--scenario", default="all", choices=["all", *SCENARIOS])
    p.add_argument("--noise", type=_noise_list, default=(0.0, 1e-5, 1e-4),
                   help="comma-separated noise std [rad], each >= 0 (default 0,1e-5,1e-4)")
    p.add_argument("--out", required=True)
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("identify", help="identify from recorded data (columns t, y, u)")
    p.add_argument("data")
    p.add_argument("--out", required=True)
    p.add_argument("--identifier", choices=["off", "lsm", "mff"], default="lsm")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="observer FMU parameter, e.g. --param b=1.12 --param 'c_nominal[1]=2'")
    p.add_argument("--input-hold", choices=["zoh", "sampled"], default="zoh",
                   help="zoh: u[k] was applied over the interval after t_k (a controller's "
                        "command, the default); sampled: u[k] samples a continuous signal")
    from .robot.cli import add_arguments as add_robot_arguments
    add_robot_arguments(p)
    p.set_defaults(func=cmd_identify)

    from .sweep import register as register_sweep
    register_sweep(sub)

    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except FMUError as error:
        print(f"harness: {error}", file=sys.stderr)
        return 2
    except KeyError as error:
        print(f"harness: {error.args[0] if error.args else error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
