"""The command line: reproduce and compare write what they promise."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_runner import cli, refused
from fmpy.util import read_csv

from harness.cli import main


def test_reproduce_writes_csv_metrics_and_figures(tmp_path, capsys, observer_fmu, pendulum_fmu,
                                                  controller_fmu):
    out = tmp_path / "results"
    code = main(["--fmu-dir", str(observer_fmu.parent), "reproduce", "--scenario", "6.1-sine",
                 "--out", str(out)])
    assert code == 0
    folder = out / "6.1-sine"
    # the quoted header reads the same with pandas and fmpy, one name per column
    signals = pd.read_csv(folder / "signals.csv")
    from_fmpy = read_csv(folder / "signals.csv")
    assert list(signals.columns[:3]) == ["time", "plant.theta", "plant.omega"]
    assert "observer.theta_hat[1][1]" in signals.columns
    assert list(signals.columns) == list(from_fmpy.dtype.names)
    assert len(signals) == 10.0 / 1e-4 / 10 + 1  # decimated by 10, plus the initial row
    for name in signals.columns:
        np.testing.assert_array_equal(signals[name].to_numpy(), from_fmpy[name])
    assert signals["time"].iloc[-1] == 10.0
    metrics = json.loads((folder / "metrics.json").read_text())
    assert 0.02 < metrics["metrics"]["rms_perturbation"] < 0.05
    assert "tau = 0.02 s" in metrics["choices"]
    for png in ("estimation_errors.png", "perturbation.png"):
        assert (folder / png).read_bytes()[:4] == b"\x89PNG"
    printed = capsys.readouterr().out
    assert "6.1-sine" in printed and "rms_perturbation" in printed


def test_compare_writes_a_side_by_side_table(tmp_path, capsys, observer_fmu, pendulum_fmu,
                                             controller_fmu):
    out = tmp_path / "compare"
    code = main(["--fmu-dir", str(observer_fmu.parent), "compare", "--scenario", "6.1-sine",
                 "--noise", "0", "--out", str(out)])
    assert code == 0
    rows = [line.split(",") for line in (out / "compare.csv").read_text().splitlines()[1:]]
    by_metric = {r[2]: (float(r[3]), float(r[4])) for r in rows}
    paper, improved = by_metric["rms_perturbation"]
    assert improved < paper / 10
    assert (out / "compare_6.1-sine_noise0.png").exists()
    assert "| 6.1-sine | 0 | rms_perturbation |" in (out / "compare.md").read_text()


def test_missing_fmus_give_a_hint_not_a_traceback(tmp_path, capsys):
    assert main(["--fmu-dir", str(tmp_path), "reproduce", "--scenario", "6.2", "--out",
                 str(tmp_path / "x")]) == 2
    assert "run ./build.sh fmus first" in capsys.readouterr().err


def test_global_options_work_after_the_command_and_every_option_has_help(tmp_path,
                                                                         observer_fmu):
    from harness.cli import build_parser

    parser = build_parser()
    for argv in (["--fmu-dir", "X", "--quiet", "reproduce", "--out", "o"],
                 ["reproduce", "--out", "o", "--fmu-dir", "X", "-q"],
                 ["sweep", "spec.json", "--out", "o", "--fmu-dir", "X", "--quiet"],
                 ["identify", "d.csv", "--out", "o", "--fmu-dir", "X", "--quiet"]):
        args = parser.parse_args(argv)
        assert args.fmu_dir == "X" and args.quiet is True, argv
    subparsers = next(a for a in parser._actions if a.choices and "sweep" in a.choices)
    for name, sub in subparsers.choices.items():
        for action in sub._actions:
            assert action.help, f"{name} {action.option_strings or action.dest} has no help"


def test_the_spec_in_sweep_help_parses(tmp_path, observer_fmu):
    import re

    from harness.cli import build_parser
    from harness.sweep import load_spec

    subparsers = next(a for a in build_parser()._actions if a.choices and "sweep" in a.choices)
    text = subparsers.choices["sweep"].format_help()
    example = re.search(r"\n    \{\n.*?\n    \}\n", text, re.S).group(0)
    (tmp_path / "spec.json").write_text(example)
    spec = load_spec(tmp_path / "spec.json", observer_fmu.parent)
    assert spec.scenario == "6.1-sine" and len(spec.runs()) > 20


def test_a_closed_pipe_ends_quietly(tmp_path):
    import subprocess
    import sys

    spec = tmp_path / "spec.json"
    spec.write_text('{"scenario": "6.1-sine", "stop_time": 2, "grid": {"observer.tau": '
                    + json.dumps([0.001 * k for k in range(1, 2000)]) + "}}")
    process = subprocess.Popen([sys.executable, "-m", "harness", "sweep", str(spec), "--out",
                                str(tmp_path / "o"), "--dry-run"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE)
    process.stdout.readline()
    process.stdout.close()  # what `| head -1` does
    err = process.stderr.read().decode()
    assert process.wait(timeout=60) == 0
    assert "Traceback" not in err and "BrokenPipe" not in err


# ---- exit status 2 for bad input ----

def recording(path: Path, n: int = 2000) -> Path:
    t = 1e-3 * np.arange(n)
    rows = np.column_stack([t, 0.1 * np.sin(2 * t) + 0.05 * np.sin(7 * t), np.cos(3 * t)])
    np.savetxt(path, rows, delimiter=",", header="t,y,u", comments="", fmt="%.17g")
    return path


@pytest.mark.cli
@pytest.mark.parametrize("param", ["novalue", "h=abc"])
def test_a_bad_param_exits_2(tmp_path, param):
    data = recording(tmp_path / "run.csv")
    code, text = cli(["identify", str(data), "--out", str(tmp_path / "o"), "--param", param])
    assert code == 2, text
    refused(code, text, "--param")


@pytest.mark.cli
def test_an_fmu_dir_without_fmus_exits_2(tmp_path):
    from harness.cli import main

    data = recording(tmp_path / "run.csv")
    code = main(["--fmu-dir", str(tmp_path), "identify", str(data), "--out",
                 str(tmp_path / "o")])
    assert code == 2
