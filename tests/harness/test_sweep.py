"""Sweeps: the spec, instance reuse, and real runs on a local Dask cluster.

The cluster is a real dask.distributed LocalCluster on loopback with two
worker processes (one thread each); the runs are 1.2 s closed-loop 6.1-sine
scenarios, so the whole module takes a few seconds beyond the cluster start.
"""
from __future__ import annotations

import argparse
import csv
import dataclasses
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from distributed import Client, LocalCluster

from harness import sweep
from harness.metrics import score
from harness.scenarios import SCENARIOS, run_scenario

STOP = 1.2  # s: just past the metrics' fixed 1-s window

SPEC = {
    "scenario": "6.1-sine",
    "stop_time": STOP,
    "grid": {"noise_std": [0.0, 1e-4]},
    "random": {"method": "lhs", "n": 2, "seed": 3, "ranges": {"observer.alpha1[1]": [2.0, 4.0]}},
    "points": [{"observer.h": -1.0}],  # the FMU rejects it: a run that fails on purpose
    "seeds": [5],
}  # 2 noise levels x 2 samples + 1 point = 5 runs


@pytest.fixture(scope="module")
def client():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as c:
        c.wait_for_workers(2, timeout=60)
        yield c


@pytest.fixture(scope="module")
def fmu_dir(observer_fmu, pendulum_fmu, controller_fmu) -> Path:
    return observer_fmu.parent


def write_spec(folder: Path, data: dict, name: str = "spec.json") -> Path:
    path = folder / name
    path.write_text(json.dumps(data))
    return path


def read_table(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


# ---- the spec ----------------------------------------------------------------

def test_spec_runs_grid_times_samples_plus_points(fmu_dir):
    spec = sweep.parse_spec(SPEC, fmu_dir)
    runs = spec.runs()
    assert len(runs) == 5
    assert len({r.key for r in runs}) == 5
    assert spec.swept == ["noise_std", "observer.alpha1[1]", "observer.h"]
    assert [r.params["noise_std"] for r in runs] == [0.0, 0.0, 1e-4, 1e-4, 0.0]
    assert runs[-1].params == {"noise_std": 0.0, "seed": 0, "observer.h": -1.0}
    # noise-free runs do not depend on the seed: seed 0; noisy runs keep theirs
    assert [r.params["seed"] for r in runs] == [0, 0, 5, 5, 0]
    # the same LHS samples for every noise level
    assert runs[0].params["observer.alpha1[1]"] == runs[2].params["observer.alpha1[1]"]


def test_latin_hypercube_puts_one_sample_in_each_stratum(fmu_dir):
    data = {"scenario": "6.2", "stop_time": 2.0,
            "random": {"method": "lhs", "n": 10, "seed": 0,
                       "ranges": {"observer.tau": {"low": 1e-3, "high": 1e-1, "scale": "log"},
                                  "observer.alpha2[1]": [10.0, 30.0]}}}
    runs = sweep.parse_spec(data, fmu_dir).runs()
    tau = np.array([r.params["observer.tau"] for r in runs])
    alpha2 = np.array([r.params["observer.alpha2[1]"] for r in runs])
    assert sorted(np.floor((np.log10(tau) + 3) / 2 * 10).astype(int)) == list(range(10))
    assert sorted(np.floor((alpha2 - 10) / 20 * 10).astype(int)) == list(range(10))
    again = sweep.parse_spec(data, fmu_dir).runs()  # the sampling seed makes it repeatable
    assert [r.key for r in again] == [r.key for r in runs]


def test_values_take_the_parameters_type_and_the_key_ignores_spelling(fmu_dir):
    a = sweep.parse_spec({"scenario": "6.2", "stop_time": 2,
                          "grid": {"observer.alpha1[1]": [8], "observer.scheme": [2.0],
                                   "observer.filter_regressor": [1]}}, fmu_dir).runs()[0]
    b = sweep.parse_spec({"scenario": "6.2", "stop_time": 2.0,
                          "grid": {"observer.filter_regressor": [True], "observer.scheme": [2],
                                   "observer.alpha1[1]": [8.0]}}, fmu_dir).runs()[0]
    assert a.params["observer.alpha1[1]"] == 8.0 and isinstance(a.params["observer.alpha1[1]"], float)
    assert a.params["observer.scheme"] == 2 and isinstance(a.params["observer.scheme"], int)
    assert a.params["observer.filter_regressor"] is True
    assert a.key == b.key
    sampled = sweep.parse_spec({"scenario": "6.2", "stop_time": 2, "random": {
        "method": "uniform", "n": 6, "ranges": {"observer.scheme": [1, 2]}}}, fmu_dir).runs()
    assert {r.params["observer.scheme"] for r in sampled} <= {1, 2}


@pytest.mark.parametrize("change, message", [
    ({"scenario": "6.9"}, "scenario '6.9' is not one of"),
    ({"grid": {"pump.x": [1]}}, "a parameter is 'fmu.variable'"),
    ({"grid": {"observer.nonsense": [1]}}, "has no variable 'nonsense'"),
    ({"grid": {"observer.x1_hat[1]": [1]}}, "is an output, not a parameter"),
    ({"grid": {"observer.alpha1[1]": ["big"]}}, "'big' is not a number"),
    ({"stop_time": 0.5}, "the metrics need a run longer than 1 s"),
    ({"random": {"n": 2, "ranges": {"observer.filter_regressor": [0, 1]}}}, "is a Boolean"),
    ({"grid": {"seed": [1, 2]}}, "either as 'seeds' or as a 'seed' parameter"),
    ({"grid": {"noise_std": [-1.0]}}, "noise_std = -1.0 must be >= 0"),
    ({"gird": {}}, "unknown spec keys ['gird']"),
])
def test_a_bad_spec_says_what_is_wrong(fmu_dir, change, message):
    with pytest.raises(sweep.SpecError) as error:
        sweep.parse_spec({**SPEC, **change}, fmu_dir)
    assert message in str(error.value)


# ---- one worker's reuse of its instances ---------------------------------------

def test_reused_instances_give_the_results_of_fresh_ones(fmu_dir):
    """fmi2Reset between runs: a run on reused instances (after another run, and
    after a run that failed) equals the same run on new instances."""
    spec = sweep.parse_spec(SPEC, fmu_dir)
    noisy = next(r for r in spec.runs() if r.params["noise_std"] > 0)
    other = next(r for r in spec.runs() if r.params["noise_std"] == 0
                 and "observer.alpha1[1]" in r.params)
    failing = spec.runs()[-1]
    pool = sweep.SimulationPool(fmu_dir)
    try:
        first = sweep.simulate(pool, *sweep.prepare(spec, noisy))
        sweep.simulate(pool, *sweep.prepare(spec, other))
        bad = sweep.simulate(pool, *sweep.prepare(spec, failing))
        again = sweep.simulate(pool, *sweep.prepare(spec, noisy))
        assert pool.size == 1  # one set of instances served every run
    finally:
        pool.close()
    assert first["status"] == again["status"] == "ok"
    assert bad["status"] == "failed" and "h = -1" in bad["message"]
    assert first["metrics"] == again["metrics"]
    scenario = dataclasses.replace(SCENARIOS["6.1-sine"], stop_time=STOP)
    fresh = run_scenario(scenario, fmu_dir, noise_std=1e-4, seed=5, observer_overrides={
        "alpha1[1]": noisy.params["observer.alpha1[1]"]})
    assert score(scenario, fresh) == first["metrics"]


def test_a_nan_metric_marks_the_run_failed(fmu_dir, monkeypatch):
    """A run whose metrics come out NaN is recorded as failed, naming the metric, with
    the other metrics kept."""
    import harness.metrics

    real_score = harness.metrics.score

    def score_with_a_nan(scenario, records):
        return {**real_score(scenario, records), "max_e2_after_1s": float("nan")}

    monkeypatch.setattr(harness.metrics, "score", score_with_a_nan)
    spec = sweep.parse_spec(SPEC, fmu_dir)
    pool = sweep.SimulationPool(fmu_dir)
    try:
        result = sweep.simulate(pool, *sweep.prepare(spec, spec.runs()[0]))
    finally:
        pool.close()
    assert result["status"] == "failed"
    assert result["message"] == "NaN metric(s): max_e2_after_1s"
    assert result["metrics"]["max_e1_after_1s"] < 1e-2


# ---- sweeps on the cluster -------------------------------------------------------

def test_sweep_on_a_local_cluster_records_failures_and_resumes(client, fmu_dir, tmp_path):
    spec = sweep.parse_spec(SPEC, fmu_dir)
    out = tmp_path / "out"
    result = sweep.run_sweep(spec, out, fmu_dir, client=client, progress=False)
    assert (result.total, result.executed, result.ok, result.failed) == (5, 5, 4, 1)
    assert result.table == out / "results.parquet"
    assert not (out / "runs").exists()  # every run file went into the table
    table = pd.read_parquet(out / "results.parquet")
    assert len(table) == 5 and table["key"].is_unique
    # the CSV export holds the same table
    exported = pd.read_csv(out / "results.csv", dtype={"message": str, "worker": str},
                           keep_default_na=False,
                           na_values={c: [""] for c in table.columns if c != "message"})
    pd.testing.assert_frame_equal(exported, table, check_dtype=False)
    failed = table[table["status"] == "failed"]
    assert len(failed) == 1
    assert failed["observer.h"].iloc[0] == -1.0
    assert "h = -1 is out of range" in failed["message"].iloc[0]
    assert table["seed"].dtype == np.int64 and table["noise_std"].dtype == np.float64
    workers = set(client.scheduler_info()["workers"][a]["name"]
                  for a in client.scheduler_info()["workers"])
    rows = table.to_dict("records")
    for r in rows:
        assert r["worker"] in {str(w) for w in workers}
        assert r["wall_time"] > 0
        if r["status"] == "ok":
            assert np.isfinite(r["max_e2_after_1s"])
            assert 0 <= r["rms_perturbation"] < 1
    # a worker's result equals the in-process run of the same parameters
    noisy = next(r for r in rows if r["status"] == "ok" and r["noise_std"] > 0)
    scenario = dataclasses.replace(SCENARIOS["6.1-sine"], stop_time=STOP)
    fresh = score(scenario, run_scenario(scenario, fmu_dir, noise_std=1e-4, seed=5,
                                         observer_overrides={"alpha1[1]": noisy["observer.alpha1[1]"]}))
    assert {k: noisy[k] for k in fresh} == fresh
    assert sorted(p.name for p in result.plots) == ["sweep_noise_std.png",
                                                    "sweep_observer.alpha1_1.png"]
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["runs"], summary["ok"], summary["failed"]) == (5, 4, 1)

    # The same sweep again: nothing to do.
    again = sweep.run_sweep(spec, out, fmu_dir, client=client, progress=False, plots=False)
    assert (again.resumed, again.executed) == (5, 0)
    pd.testing.assert_frame_equal(pd.read_parquet(out / "results.parquet"), table)

    # A killed sweep: the table holds two runs, a third finished run is only in its run
    # file, a fourth run's file was never renamed into place (both in the manifest); a
    # file of someone else's in runs/ is not the sweep's to read or remove.
    table.iloc[:2].to_parquet(out / "results.parquet")
    (out / "runs").mkdir()
    table.iloc[2:3].to_parquet(out / "runs" / f"{table['key'].iloc[2]}.parquet")
    (out / "runs" / f".{table['key'].iloc[3]}.parquet.123.tmp").write_bytes(b"PAR1 half")
    (out / "runs" / "MANIFEST").write_text(f"{table['key'].iloc[2]}.parquet\n"
                                           f"{table['key'].iloc[3]}.parquet\n")
    (out / "runs" / "junk.parquet").write_bytes(b"not parquet")
    resumed = sweep.run_sweep(spec, out, fmu_dir, client=client, progress=False, plots=False)
    assert (resumed.resumed, resumed.executed) == (3, 2)
    after = pd.read_parquet(out / "results.parquet")
    assert len(after) == 5 and after["key"].is_unique
    pd.testing.assert_frame_equal(after.iloc[:3], table.iloc[:3])
    assert (out / "runs" / "junk.parquet").read_bytes() == b"not parquet"
    assert not (out / "runs" / "MANIFEST").exists()

    # A wider grid runs only the new points; --retry-failed redoes the failed run only.
    wider = sweep.parse_spec({**SPEC, "grid": {"noise_std": [0.0, 1e-5, 1e-4]}}, fmu_dir)
    grown = sweep.run_sweep(wider, out, fmu_dir, client=client, progress=False, plots=False)
    assert (grown.total, grown.resumed, grown.executed, grown.failed) == (7, 5, 2, 0)
    retried = sweep.run_sweep(wider, out, fmu_dir, client=client, progress=False, plots=False,
                              retry_failed=True)
    assert (retried.executed, retried.failed) == (1, 1)
    assert len(pd.read_parquet(out / "results.parquet")) == 7
    assert len(read_table(out / "results.csv")) == 7


def test_rows_are_on_disk_as_each_run_completes(fmu_dir, tmp_path):
    """Each appended row is a file of its own at once; a new table reads them back with
    their types, a retried run's row replacing the older one."""
    spec = sweep.parse_spec(SPEC, fmu_dir)
    runs = spec.runs()
    table = sweep.ResultsTable(tmp_path)
    table.append(sweep.result_row(spec, runs[0], {"status": "failed", "message": "x, y"}))
    table.append(sweep.result_row(spec, runs[1], {"status": "ok", "wall_time": 0.5,
                                                  "metrics": {"delay": 0.01}}))
    table.append(sweep.result_row(spec, runs[0], {"status": "ok", "metrics": {"delay": 0.02}}))
    assert sorted(p.name for p in (tmp_path / "runs").iterdir()) == sorted(
        [f"{r.key}.parquet" for r in runs[:2]] + ["MANIFEST"])
    again = sweep.ResultsTable(tmp_path)
    assert again.status() == {runs[0].key: "ok", runs[1].key: "ok"}
    rows = {r["key"]: r for r in again.rows({runs[0].key, runs[1].key})}
    first, second = rows[runs[0].key], rows[runs[1].key]
    assert first["delay"] == 0.02 and "wall_time" not in first and second["wall_time"] == 0.5
    assert second["observer.alpha1[1]"] == runs[1].params["observer.alpha1[1]"]
    again.consolidate([runs[1].key, runs[0].key])
    assert list(pd.read_parquet(tmp_path / "results.parquet")["key"]) == [runs[1].key,
                                                                          runs[0].key]
    assert not (tmp_path / "runs").exists()


def test_command_line_with_a_running_scheduler(client, fmu_dir, tmp_path, capsys):
    """``sweep SPEC --out DIR --scheduler ADDRESS``, through the CLI's subparser."""
    spec = write_spec(tmp_path, {"scenario": "6.1-sine", "stop_time": STOP,
                                 "grid": {"observer.tau": [0.02, 0.005]}})
    parser = argparse.ArgumentParser()
    parser.add_argument("--fmu-dir", default=str(fmu_dir))
    sweep.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["sweep", str(spec), "--out", str(tmp_path / "cli"),
                              "--scheduler", client.scheduler.address, "--no-plots"])
    assert args.func(args) == 0
    printed = capsys.readouterr()
    assert "2 run now: 2 ok, 0 failed" in printed.out
    assert "2/2 runs" in printed.err  # the progress counter
    assert len(pd.read_parquet(tmp_path / "cli" / "results.parquet")) == 2
    assert len(read_table(tmp_path / "cli" / "results.csv")) == 2
    # the worker plugin is gone again: the shared cluster keeps no FMU instances
    plugins = client.run(lambda dask_worker: sorted(dask_worker.plugins))
    assert not any(name.startswith("sto-sweep-fmus-") for names in plugins.values()
                   for name in names)

    args = parser.parse_args(["sweep", str(spec), "--out", str(tmp_path / "cli"), "--dry-run"])
    assert args.func(args) == 0
    assert capsys.readouterr().out.count("  ok  ") == 2


def test_a_folder_of_an_earlier_version_resumes_from_its_csv(fmu_dir, tmp_path):
    spec = sweep.parse_spec(SPEC, fmu_dir)
    run = spec.runs()[0]
    (tmp_path / "results.csv").write_text(f"key,status,message,observer.alpha1[1]\n"
                                          f"{run.key},ok,,{run.params['observer.alpha1[1]']!r}\n")
    table = sweep.ResultsTable(tmp_path)
    assert table.status() == {run.key: "ok"}
    assert table.rows({run.key})[0]["observer.alpha1[1]"] == run.params["observer.alpha1[1]"]
