"""The closed loop as an SSP file that other tools simulate like the harness does."""
from __future__ import annotations

import dataclasses
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from cli_runner import FMU_DIR, REPO
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import read_ssd

from harness.scenarios import SCENARIOS, run_scenario
from harness.ssp import fmpy_arguments, write_ssp

SECONDS = 5.0  # of the 40 s of 6.2: fmpy's SSP loop is plain Python (2.5 s per model second)
ESTIMATES = [f"observer.theta_hat[1,{k}]" for k in (1, 2, 3)]


@pytest.fixture(scope="module")
def ssp(tmp_path_factory, observer_fmu, pendulum_fmu, controller_fmu):
    return write_ssp(observer_fmu.parent, tmp_path_factory.mktemp("ssp") / "ClosedLoop.ssp",
                     "6.2")


@pytest.fixture(scope="module")
def harness_run(observer_fmu):
    return run_scenario(dataclasses.replace(SCENARIOS["6.2"], stop_time=SECONDS),
                        observer_fmu.parent)


def test_the_ssd_is_valid_and_declares_the_observers_outputs(ssp):
    ssd = read_ssd(str(ssp))  # validates against the SSP schema
    assert sorted(c.name for c in ssd.system.elements) == ["controller", "observer", "plant"]
    assert len(ssd.system.connections) == 5
    observer = next(c for c in ssd.system.elements if c.name == "observer")
    outputs = {c.name for c in observer.connectors if c.kind == "output"}
    assert {"x1_hat[1]", "x2_hat[1]", "z_eq_filtered[1]", "theta_hat[1,1]"} <= outputs
    arguments = fmpy_arguments(ssp)
    assert arguments["step_size"] == 1e-4 and arguments["stop_time"] == 40.0
    typed = {p.name: p.value for p in arguments["parameter_set"].parameters}
    assert typed["observer.filter_regressor"] is False  # fmpy alone would set it True
    assert typed["observer.scheme"] == 1 and typed["observer.c_nominal[1]"] == 2.0


def test_fmpy_simulate_ssp_reproduces_the_harness(ssp, harness_run):
    arguments = {**fmpy_arguments(ssp), "stop_time": SECONDS}
    result = simulate_ssp(str(ssp), **arguments)
    # fmpy records the values after each step against the step's start time
    t = result["time"] + arguments["step_size"]
    theta = np.interp(t, harness_run.time, harness_run["plant.theta"])
    assert np.max(np.abs(result["plant.theta"] - theta)) < 2e-3  # rad, of a 0.9 rad swing
    for name in ESTIMATES:  # fmpy steps the FMUs in parallel: one sample more loop delay
        assert result[name][-1] == pytest.approx(harness_run[name][-1], rel=0.02), name
    # without the bindings the observer runs on its defaults: a different result
    plain = simulate_ssp(str(ssp), stop_time=0.5, step_size=arguments["step_size"])
    assert plain["observer.theta_hat[1,1]"][-1] != pytest.approx(
        np.interp(0.5, harness_run.time, harness_run["observer.theta_hat[1,1]"]), rel=0.02)


def test_libcosim_loads_and_simulates_it(ssp, harness_run, tmp_path):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver

    zipfile.ZipFile(ssp).extractall(tmp_path)
    execution = CosimExecution.from_ssp_file(str(tmp_path))  # step from the OSP annotation
    assert execution.num_slaves() == 3
    values = CosimObserver.create_last_value()
    execution.add_observer(values)
    execution.simulate_until(int(SECONDS * 1e9))
    index = execution.slave_index_from_instance_name("observer")
    references = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    names = [n.removeprefix("observer.") for n in ESTIMATES] + ["c_nominal[1]", "alpha1[1]"]
    got = values.last_real_values(index, [references[n] for n in names])
    assert got[3:] == [2.0, 8.0]  # the scenario's parameters, bound in the SSD
    for value, name in zip(got, ESTIMATES):
        assert value == pytest.approx(harness_run[name][-1], rel=0.02), name


# ---- outputs: harness.ssp refuses to overwrite its inputs, writes all or nothing ----

def leftovers(folder: Path) -> list[Path]:
    """Temporaries of the output machinery left in ``folder``."""
    return [p for p in folder.rglob("*") if "sto-partial" in p.name or p.name.endswith(".tmp")]


@pytest.mark.cli
def test_ssp_refuses_to_write_over_an_fmu(tmp_path):
    fmus = tmp_path / "fmus"
    shutil.copytree(FMU_DIR, fmus)
    before = (fmus / "Pendulum.fmu").read_bytes()
    result = subprocess.run([sys.executable, "-m", "harness.ssp", str(fmus),
                             str(fmus / "Pendulum.fmu")], cwd=REPO, capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 2, result.stderr
    assert "Pendulum.fmu" in result.stderr and "Traceback" not in result.stderr
    assert (fmus / "Pendulum.fmu").read_bytes() == before


@pytest.mark.cli
def test_ssp_into_a_folder_name_is_refused(tmp_path):
    from harness.ssp import main

    folder = tmp_path / "loop.ssp"
    folder.mkdir()
    assert main([str(FMU_DIR), str(folder)]) == 2
    assert not any(folder.iterdir()) and not leftovers(tmp_path)


@pytest.mark.cli
def test_ssp_with_an_fmu_missing_writes_nothing(tmp_path):
    from harness.ssp import main

    fmus = tmp_path / "fmus"
    shutil.copytree(FMU_DIR, fmus)
    (fmus / "TwistingController.fmu").unlink()
    out = tmp_path / "out" / "loop.ssp"
    assert main([str(fmus), str(out)]) == 2
    assert not out.exists() and not leftovers(tmp_path)
