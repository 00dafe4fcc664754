"""The FMUs in independent FMI importers (tools/importers/check.py), and the reference they ship.

The importers (FMI4j, fmi-sim) are installed by tools/importers/install.sh, not by
build.sh: without them these tests FAIL (never skip) and say so.
"""
from __future__ import annotations

import shutil
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tools.importers import check
from tools.importers import make_reference as mr

REPO = Path(__file__).resolve().parents[2]

INSTALL = "run tools/importers/install.sh (FMI4j and fmi-sim), then run the tests again"


def test_importers_are_installed():
    problems = check.check_tools()
    if problems:
        pytest.fail("importers missing:\n  " + "\n  ".join(problems) + f"\n{INSTALL}")


def model_file_fmu(tmp_path: Path) -> Path:
    """A model file's FMU as `sto-harness fmu --model` writes it (the EMPS drive), with
    its default experiment as its reference: each importer must hand it its resources."""
    from harness.cli import main

    assert main(["fmu", "--model", str(REPO / "examples" / "emps" / "emps.toml"),
                 "--out", str(tmp_path)]) == 0
    mr.main([str(tmp_path / "emps.fmu")])
    return tmp_path / "emps.fmu"


def test_every_fmu_agrees_with_its_reference_in_every_importer(observer_fmu, pendulum_fmu,
                                                                 controller_fmu, robot_fmu,
                                                                 tmp_path):
    problems = check.check_tools()
    if problems:
        pytest.fail("importers missing:\n  " + "\n  ".join(problems) + f"\n{INSTALL}")
    fmus = [observer_fmu, pendulum_fmu, controller_fmu, robot_fmu,
            observer_fmu.with_name("ModelObserver.fmu"), model_file_fmu(tmp_path)]
    run = subprocess.run([sys.executable, "-m", "tools.importers.check", *map(str, fmus)],
                         capture_output=True, text=True, cwd=REPO, timeout=1800)
    print(run.stdout)
    assert run.returncode == 0, f"check.py failed:\n{run.stdout}\n{run.stderr}"
    assert f"{4 * len(fmus)} passed, 0 failed" in run.stdout


def test_reference_embedding_is_idempotent_and_read_back_exactly(tmp_path, controller_fmu):
    fmu = tmp_path / controller_fmu.name
    shutil.copy(controller_fmu, fmu)
    fmu.chmod(0o644)
    mr.main([str(fmu)])
    first = fmu.read_bytes()
    mr.main([str(fmu)])
    assert fmu.read_bytes() == first
    assert stat.S_IMODE(fmu.stat().st_mode) == 0o644  # the rewrite keeps the file's mode

    with zipfile.ZipFile(fmu) as archive:
        names = archive.namelist()
    assert names.count(mr.MANIFEST) == 1
    assert "extra/org.fmi-standard.fmi-ls-ref/TwistingController_out.csv" in names
    # every member of the original FMU is still there, unchanged
    with zipfile.ZipFile(controller_fmu) as original, zipfile.ZipFile(fmu) as rewritten:
        for info in original.infolist():
            if not mr.is_ls_ref_member(info.filename):
                assert rewritten.read(info.filename) == original.read(info.filename)

    ref = mr.read_reference(fmu)
    desc = mr.read_description(fmu)
    times, columns = mr.simulate(fmu, desc)
    every = desc.experiment.decimation
    assert ref.header == ["time"] + [label for label, _, _, _ in desc.columns]
    assert len(ref.times) == desc.experiment.steps // every + 1
    for name, values in ref.columns.items():
        np.testing.assert_array_equal(values, columns[name][::every])  # bit-exact round trip


def test_comparison_catches_a_one_step_offset():
    """The tolerance has teeth: a result one communication step late fails by far."""
    t = np.linspace(0.0, 1.0, 1001)
    step = 1e-3
    signal = np.sin(2 * np.pi * t)
    ref = mr.Reference("x.csv", ["time", "y"], t[::10], {"y": signal[::10]})
    same = check.compare(ref, t, {"y": signal.copy()}, step, 1e-9)
    assert same.deviation == 0 and not same.problems and same.interpolated == 0
    late = check.compare(ref, t, {"y": np.concatenate([signal[:1], signal[:-1]])}, step, 1e-9)
    assert late.deviation > 1e-3 and late.problems
    missing = check.compare(ref, t, {"z": signal}, step, 1e-9)
    assert missing.problems == ["no column 'y'"]
    short = check.compare(ref, t[:500], {"y": signal[:500]}, step, 1e-9)
    assert short.problems and "covers" in short.problems[0]


def test_fmi3_fmus_ship_the_same_reference_as_their_fmi2_variants(fmi3_fmu):
    """Same model files, same numbers: the FMI 3 result (arrays as element columns) is the
    FMI 2 result, to the last bit."""
    from tests.conftest import fmu_path

    fmi2 = mr.read_reference(fmu_path(fmi3_fmu.stem, 2))
    fmi3 = mr.read_reference(fmi3_fmu)
    assert fmi3.header == fmi2.header and len(fmi3.header) > 3
    np.testing.assert_array_equal(fmi3.times, fmi2.times)
    for name in fmi2.header[1:]:
        np.testing.assert_array_equal(fmi3.columns[name], fmi2.columns[name], err_msg=name)
    with zipfile.ZipFile(fmi3_fmu) as archive:
        assert "fmi3DoStep" in archive.read(mr.DOC).decode()
