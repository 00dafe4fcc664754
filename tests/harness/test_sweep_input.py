"""harness sweep against bad specs, bad options, concurrent writers and kills.

Specs: every number is checked (NaN, Infinity, huge, non-integral or wrapped
Integers, bad seeds, a NaN transient) and a spec of more than MAX_RUNS runs
is refused at once, before any run list is built.  Options: --workers and an
unreachable or worker-less scheduler end with a message, never a hang.  The
output folder has one writer at a time (a second sweep is refused, nothing
is lost), the exit status says whether every run succeeded, and FMUs
extracted by killed sweeps are removed by the next one.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from cli_runner import FMU_DIR, REPO, cli, refused, shell

from harness import sweep
from harness.sweep import plan as sweep_plan
from harness.sweep.spec import MAX_RUNS, SpecError

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code

STOP = 1.2
BASE = {"scenario": "6.1-sine", "stop_time": STOP}
BIG = int("9" * 400)


def spec_file(folder: Path, data: dict | str) -> Path:
    path = folder / "spec.json"
    path.write_text(data if isinstance(data, str) else json.dumps(data, allow_nan=True))
    return path


def dry_run(tmp_path: Path, data: dict | str) -> tuple[int, str]:
    return cli(["sweep", str(spec_file(tmp_path, data)), "--out", str(tmp_path / "out"),
                "--dry-run"])


# ---- values in a spec ------------------------------------------------------------------------

BAD_VALUES = [
    ("observer.scheme", "Infinity", "is not an integer"),
    ("observer.scheme", "-Infinity", "is not an integer"),
    ("observer.scheme", "NaN", "is not an integer"),
    ("observer.scheme", "4294967298", "out of range [1, 3]"),
    ("observer.scheme", "-4294967294", "out of range"),
    ("observer.scheme", "2147483648", "out of range"),
    ("observer.scheme", "1.5", "is not an integer"),
    ("observer.scheme", "4", "observer.scheme = 4 is out of range [1, 3]"),
    ("observer.scheme", "0", "out of range [1, 3]"),
    ("observer.scheme", str(BIG), "out of range"),
    ("observer.scheme", "1e400", "is not an integer"),
    ("observer.scheme", "true", "is not a number"),
    ("observer.max_internal_steps", "0", "out of range [1, 2147483647]"),
    ("plant.damping", "2", "out of range [0, 1]"),
    ("observer.tau", "Infinity", "is not finite"),
    ("observer.tau", "NaN", "is not finite"),
    ("observer.tau", str(BIG), "too large"),
    ("observer.tau", "\"0.1\"", "is not a number"),
    ("observer.filter_regressor", "2", "is not a Boolean"),
    ("observer.filter_regressor", "NaN", "is not a Boolean"),
    ("noise_std", "Infinity", "not finite"),
    ("noise_std", "NaN", "not finite"),
    ("noise_std", "-1e-5", "must be >= 0"),
    ("seed", "-1", "out of range"),
    ("seed", "1.5", "is not an integer"),
    ("seed", "NaN", "is not an integer"),
    ("seed", str(BIG), "out of range"),
]


@pytest.mark.parametrize("where", ["grid", "fixed", "points"])
@pytest.mark.parametrize("name, value, words", BAD_VALUES,
                         ids=[f"{n}={v[:12]}" for n, v, _ in BAD_VALUES])
def test_a_bad_value_is_a_spec_error(tmp_path, where, name, value, words):
    if where == "grid":
        text = f'{{"scenario": "6.1-sine", "stop_time": {STOP}, "grid": {{"{name}": [{value}]}}}}'
    elif where == "fixed":
        text = f'{{"scenario": "6.1-sine", "stop_time": {STOP}, "fixed": {{"{name}": {value}}}}}'
    else:
        text = f'{{"scenario": "6.1-sine", "stop_time": {STOP}, "points": [{{"{name}": {value}}}]}}'
    if name == "seed" and where != "points":
        text = text.replace('"grid": {"seed"', '"seeds": {').replace('"fixed": {"seed"', '"x": {')
        if where == "fixed":
            text = f'{{"scenario": "6.1-sine", "stop_time": {STOP}, "seeds": [{value}]}}'
        else:
            text = f'{{"scenario": "6.1-sine", "stop_time": {STOP}, "seeds": [{value}], ' \
                   f'"grid": {{"noise_std": [1e-5]}}}}'
    code, out = dry_run(tmp_path, text)
    refused(code, out, words)


@pytest.mark.parametrize("change, words", [
    ({"transient": float("nan")}, "transient = nan is not finite"),
    ({"transient": float("inf")}, "transient = inf is not finite"),
    ({"transient": -1}, "transient = -1"),
    ({"transient": "1"}, "is not a number"),
    ({"stop_time": float("inf")}, "stop_time = inf is not finite"),
    ({"stop_time": float("nan")}, "not finite"),
    ({"stop_time": 1e300}, "stop_time = 1e+300 is out of range (0, 10000]"),
    ({"stop_time": BIG}, "stop_time = a huge number is out of range"),
    ({"random": {"n": 2, "seed": -1, "ranges": {"observer.tau": [0.001, 0.01]}}},
     "random.seed = -1 is out of range [0, 9223372036854775807]"),
    ({"random": {"n": 2, "seed": "abc", "ranges": {"observer.tau": [0.001, 0.01]}}},
     "random.seed = 'abc' is not an integer"),
    ({"random": {"n": 2, "seed": 1.5, "ranges": {"observer.tau": [0.001, 0.01]}}},
     "random.seed = 1.5 is not an integer"),
    ({"random": {"n": 2, "seed": BIG, "ranges": {"observer.tau": [0.001, 0.01]}}},
     "random.seed = a huge number is out of range"),
    ({"random": {"n": 2, "ranges": {"observer.tau": [float("-inf"), float("inf")]}}},
     "is not finite"),
    ({"random": {"n": 2, "ranges": {"observer.tau": [0.001, float("nan")]}}}, "is not finite"),
    ({"random": {"n": 2, "ranges": {"observer.tau": [0.001, BIG]}}}, "too large"),
    ({"random": {"n": 2, "ranges": {"observer.scheme": [1, 5e9]}}}, "is not inside the Integer"),
    ({"random": {"n": 2.5, "ranges": {"observer.tau": [0.001, 0.01]}}}, "random.n = 2.5 is not an integer"),
    ({"random": {"n": 10**9, "ranges": {"observer.tau": [0.001, 0.01]}}}, "random.n = 1000000000 is out of range [1, 100000]: a sweep has at most"),
    ({"seeds": 10**9}, f"seeds = 1000000000 is out of range [1, {MAX_RUNS}]: a sweep has at most"),
    ({"seeds": BIG}, "seeds = a huge number"),
    ({"seeds": -1}, "seeds = -1"),
    ({"scenario": ["6.2"]}, "is not one of"),
    ({"method": {"x": 1}}, "is not one of"),
    ({"points": {"observer.tau": 1}}, "points = {'observer.tau': 1} is not a list"),
])
def test_a_bad_spec_entry_is_a_spec_error(tmp_path, change, words):
    code, out = dry_run(tmp_path, {**BASE, **change})
    refused(code, out, words)


def test_integer_samples_of_a_range_are_rounded_and_in_range(tmp_path):
    spec = sweep.parse_spec({**BASE, "random": {"n": 20, "method": "uniform",
                                                "ranges": {"observer.scheme": [1, 3]}}}, FMU_DIR)
    values = {r.params["observer.scheme"] for r in spec.runs()}
    assert values <= {1, 2, 3} and all(isinstance(v, int) for v in values)


# ---- the number of runs ----------------------------------------------------------------------

@pytest.mark.parametrize("change", [
    {"grid": {"observer.tau": [0.001 * (k + 1) for k in range(1000)],
              "observer.alpha1[1]": [1.0 + k for k in range(1000)],
              "observer.alpha2[1]": [1.0 + k for k in range(100)]}},
    {"seeds": 1_000_000_000, "grid": {"noise_std": [1e-5]}},
    {"grid": {"observer.tau": [0.001 * (k + 1) for k in range(1000)]},
     "random": {"n": 101, "ranges": {"observer.alpha1[1]": [1, 2]}}},
    {"points": [{"observer.tau": 0.001 + k * 1e-6} for k in range(MAX_RUNS + 1)]},
    {"grid": {"observer.tau": [0.001 * (k + 1) for k in range(400)]}, "seeds": 251},
])
def test_too_many_runs_are_refused_at_once(tmp_path, monkeypatch, change):
    code, out = dry_run(tmp_path, {**BASE, **change})
    refused(code, out, f"{MAX_RUNS}", "a sweep ")
    assert "runs" in out
    # refused from the counts, before any run list is built (was a 10 s wall-clock bound,
    # which a loaded machine broke: 10.9 s)
    def no_run_list(self: sweep_plan.SweepSpec) -> list:
        raise AssertionError("the run list was built before refusing")

    monkeypatch.setattr(sweep_plan.SweepSpec, "runs", no_run_list)
    with pytest.raises(SpecError, match=f"{MAX_RUNS}"):
        sweep.parse_spec({**BASE, **change}, FMU_DIR)


def test_the_largest_sweep_is_accepted(tmp_path):
    data = {**BASE, "grid": {"observer.tau": [0.001 * (k + 1) for k in range(100)]},
            "random": {"n": 1000, "ranges": {"observer.alpha1[1]": [1, 2]}}}
    spec = sweep.parse_spec(data, FMU_DIR)
    assert len(spec.runs()) == MAX_RUNS


# ---- --workers and the scheduler ---------------------------------------------------------------

@pytest.mark.parametrize("workers, words", [("-1", "out of range [1, 1024]"),
                                            ("0", "out of range"), ("1.5", "is not an integer"),
                                            ("abc", "is not a number"), ("100000", "out of range"),
                                            ("nan", "is not an integer")])
def test_bad_worker_counts_are_refused_at_once(tmp_path, workers, words):
    start = time.monotonic()
    code, out = cli(["sweep", str(spec_file(tmp_path, BASE)), "--out", str(tmp_path / "o"),
                     "--workers", workers])
    refused(code, out, "--workers", words)
    assert time.monotonic() - start < 10
    assert not (tmp_path / "o").exists()


def test_library_refuses_bad_worker_counts(tmp_path):
    spec = sweep.parse_spec(BASE, FMU_DIR)
    for n in (-1, 0, 10**6):
        with pytest.raises(sweep.ClusterError, match="give 1 .. 1024 worker processes"):
            sweep.run_sweep(spec, tmp_path / f"o{n}", FMU_DIR, n_workers=n, progress=False)


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:9", "tcp://127.0.0.1:1", "nonsense://x",
                                     "tcp://256.0.0.1:8786"])
def test_an_unreachable_scheduler_is_an_error_not_a_hang(tmp_path, address):
    start = time.monotonic()
    code, out = cli(["sweep", str(spec_file(tmp_path, BASE)), "--out", str(tmp_path / "o"),
                     "--scheduler", address, "--connect-timeout", "2"])
    refused(code, out, "cannot connect to the Dask scheduler at")
    assert time.monotonic() - start < 30


def test_a_scheduler_without_workers_is_an_error_not_a_hang(tmp_path):
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=True, host="127.0.0.1",
                      dashboard_address=None) as empty:
        start = time.monotonic()
        code, out = cli(["sweep", str(spec_file(tmp_path, BASE)), "--out", str(tmp_path / "o"),
                         "--scheduler", empty.scheduler_address, "--connect-timeout", "2"])
    refused(code, out, "has no workers (none came up within 2 s)")
    assert time.monotonic() - start < 30


@pytest.mark.parametrize("value", ["0", "-1", "nan", "abc"])
def test_bad_connect_timeouts_are_refused(tmp_path, value):
    code, out = cli(["sweep", str(spec_file(tmp_path, BASE)), "--out", str(tmp_path / "o"),
                     "--connect-timeout", value])
    refused(code, out, "--connect-timeout")


# ---- exit status -----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def scheduler():
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        yield cluster.scheduler_address


@pytest.mark.parametrize("points, expect", [
    ([{"observer.h": -1.0}, {"observer.tau": -1.0}], 1),     # every run failed
    ([{"observer.h": -1.0}, {"observer.tau": 0.01}], 1),     # some failed
    ([{"observer.tau": 0.02}, {"observer.tau": 0.01}], 0),   # every run ok
])
def test_exit_status_says_whether_every_run_succeeded(tmp_path, scheduler, points, expect):
    path = spec_file(tmp_path, {**BASE, "points": points})
    args = ["sweep", str(path), "--out", str(tmp_path / "o"), "--scheduler", scheduler,
            "--no-plots"]
    code, out = cli(args)
    assert code == expect, out
    if expect:
        assert "runs failed" in out
    again, out = cli(args)  # nothing left to run: the table still decides
    assert again == expect, out


def test_a_results_table_that_is_not_one_is_an_error(tmp_path, scheduler):
    out = tmp_path / "o"
    out.mkdir()
    (out / "results.csv").write_text("name,value\nx,1\n")
    path = spec_file(tmp_path, BASE)
    for extra in (["--dry-run"], ["--scheduler", scheduler]):
        code, text = cli(["sweep", str(path), "--out", str(out), *extra])
        refused(code, text, "is not a sweep results table")
    assert (out / "results.csv").read_text() == "name,value\nx,1\n"


def test_out_naming_a_file_is_refused(tmp_path):
    target = tmp_path / "f"
    target.write_text("x")
    code, text = cli(["sweep", str(spec_file(tmp_path, BASE)), "--out", str(target)])
    refused(code, text, "exists and is not a folder")


# ---- one writer per output folder ------------------------------------------------------------

HOLD = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from harness.sweep.lock import locked_output
    with locked_output(Path(sys.argv[1])):
        print("held", flush=True)
        time.sleep(120)
""")


def _holder(out: Path) -> subprocess.Popen:
    process = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], cwd=REPO,
                               stdout=subprocess.PIPE, text=True)
    assert process.stdout.readline().strip() == "held"
    return process


def test_a_second_writer_is_refused_and_a_killed_one_leaves_no_lock(tmp_path, scheduler):
    out = tmp_path / "o"
    table = out / "results.csv"
    path = spec_file(tmp_path, {**BASE, "points": [{"observer.tau": 0.02}]})
    holder = _holder(out)
    try:
        start = time.monotonic()
        code, text = cli(["sweep", str(path), "--out", str(out), "--scheduler", scheduler])
        assert code == 3, text
        refused(code, text, f"another sweep is writing to {out}")
        assert time.monotonic() - start < 10, "it waited for the lock"
        assert not table.exists()
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    code, text = cli(["sweep", str(path), "--out", str(out), "--scheduler", scheduler,
                      "--no-plots"])
    assert code == 0, text
    assert len(table.read_text().splitlines()) == 2


def test_two_sweeps_into_one_folder_lose_nothing(tmp_path):
    """Two real sweep processes at once: one runs, the other is refused (exit 3) or runs
    after it; no finished run is lost and no row is duplicated."""
    out = tmp_path / "o"
    specs = [spec_file(tmp_path / str(i), {**BASE, "grid": {"observer.tau": taus}})
             for i, taus in ((1, [0.02, 0.01]), (2, [0.005, 0.003]))
             if (tmp_path / str(i)).mkdir() is None]
    processes = [subprocess.Popen([sys.executable, "-m", "harness", "--fmu-dir", str(FMU_DIR),
                                   "sweep", str(s), "--out", str(out), "--workers", "1",
                                   "--no-plots"], cwd=REPO, stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True) for s in specs]
    results = [(p.wait(timeout=300), p.stdout.read() + p.stderr.read()) for p in processes]
    codes = sorted(code for code, _ in results)
    assert codes in ([0, 0], [0, 3]), results
    for _, text in results:
        assert "Traceback" not in text
    rows = (out / "results.csv").read_text().splitlines()[1:]
    expected = 4 if codes == [0, 0] else 2
    assert len(rows) == expected and len({r.split(",")[0] for r in rows}) == expected
    if codes == [0, 3]:  # the refused one, again: now it runs, and both sets are kept
        refused_spec = specs[[c for c, _ in results].index(3)]
        result = shell(["sweep", str(refused_spec), "--out", str(out), "--workers", "1",
                        "--no-plots"], timeout=300)
        assert result.returncode == 0, result.stdout + result.stderr
        assert len((out / "results.csv").read_text().splitlines()) == 5


# ---- extracted FMUs of killed processes ---------------------------------------------------------

LEAVE = textwrap.dedent("""
    import os, signal, sys
    from harness.fmus import FMUInstance
    fmu = FMUInstance(sys.argv[1], "leaked")
    print(fmu._unzip_dir, flush=True)
    os.kill(os.getpid(), signal.SIGKILL)
""")


def _killed_process_folder(tmp_path: Path) -> Path:
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", LEAVE, str(FMU_DIR / "Pendulum.fmu")],
                            cwd=REPO, capture_output=True, text=True, env=env, timeout=60)
    assert result.returncode == -signal.SIGKILL
    folder = Path(result.stdout.strip())
    assert folder.parent == tmp_path and folder.is_dir()
    return folder


def test_stale_folders_are_removed_and_live_ones_kept(tmp_path):
    from harness.tempdirs import owned_temp_dir, remove_stale

    stale = _killed_process_folder(tmp_path)
    mine = owned_temp_dir("fmu", tmp_path)
    unrelated = tmp_path / "sto-notes"
    unrelated.mkdir()
    assert remove_stale(tmp_path) == [stale]
    assert not stale.exists() and mine.exists() and unrelated.exists()


def test_the_next_sweep_removes_what_killed_ones_left(tmp_path, monkeypatch):
    import tempfile

    stale = [_killed_process_folder(tmp_path) for _ in range(3)]
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    spec = sweep.parse_spec({**BASE, "points": [{"observer.tau": 0.02}]}, FMU_DIR)
    out = tmp_path / "o"
    out.mkdir()
    # a table that already holds the run: the sweep needs no cluster, only its start-up
    row = sweep.result_row(spec, spec.runs()[0], {"status": "ok", "metrics": {}})
    sweep.ResultsTable(out).append(row)
    result = sweep.run_sweep(spec, out, FMU_DIR, progress=False, plots=False)
    assert result.executed == 0
    assert not any(p.exists() for p in stale)


def test_a_killed_sweep_leaves_nothing_after_the_next_run(tmp_path):
    """kill -9 of a real sweep mid-run, then the same sweep again: it resumes, and
    no extracted FMU of a dead process stays in the temp folder."""
    env = {**os.environ, "TMPDIR": str(tmp_path / "tmp")}
    (tmp_path / "tmp").mkdir()
    path = spec_file(tmp_path, {**BASE, "grid": {"observer.tau": [0.02, 0.01, 0.005, 0.003]}})
    args = [sys.executable, "-m", "harness", "--fmu-dir", str(FMU_DIR), "sweep", str(path),
            "--out", str(tmp_path / "o"), "--workers", "1", "--no-plots"]
    process = subprocess.Popen(args, cwd=REPO, env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not list((tmp_path / "tmp").glob("sto-fmu-*")):
        time.sleep(0.2)
    time.sleep(1.0)
    os.killpg(process.pid, signal.SIGKILL)  # the sweep and its cluster, as a kill of the job
    process.wait()
    time.sleep(0.5)
    result = subprocess.run(args, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    from harness.tempdirs import _NAME, _alive
    left = [p for p in (tmp_path / "tmp").iterdir()
            if _NAME.match(p.name) and not _alive(int(_NAME.match(p.name).group(2)))]
    assert not left, left
    rows = (tmp_path / "o" / "results.csv").read_text().splitlines()[1:]
    assert len(rows) == 4 and len({r.split(",")[0] for r in rows}) == 4
