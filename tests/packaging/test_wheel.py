"""The wheel the build makes installs a working harness, with its dependencies declared."""
from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
import sysconfig
import zipfile
from importlib.metadata import packages_distributions
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
WHEELS = sorted((REPO / "build" / "wheel").glob("sto_harness-*.whl"))


@pytest.fixture(scope="module")
def wheel() -> Path:
    assert WHEELS, "no wheel in build/wheel: ./build.sh wheel (or test) makes it"
    return WHEELS[-1]


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> Path:
    """A fresh venv with the wheel installed by pip, offline: the dependencies come from
    the build's .venv (a .pth file), so pip checks that they are declared and present."""
    venv = tmp_path_factory.mktemp("venv") / "v"
    subprocess.run([sys._base_executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()"
                           "['purelib'])"], capture_output=True, text=True, check=True)
    Path(site.stdout.strip(), "build_venv.pth").write_text(sysconfig.get_paths()["purelib"]
                                                           + "\n")
    subprocess.run([str(python), "-m", "pip", "install", "--no-index", "--quiet",
                    "--disable-pip-version-check", str(wheel)], check=True)
    return venv


def _clean_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("STO_FMU_DIR", "PYTHONPATH")}
    env["MPLBACKEND"] = "Agg"
    return env


def test_the_wheel_ships_the_fmus_types_and_native_library(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    for name in ("harness/data/SuperTwistingObserver.fmu", "harness/data/Pendulum.fmu",
                 "harness/data/TwistingController.fmu", "harness/data/RobotObserver.fmu",
                 "harness/data/ModelObserver.fmu", "harness/data/fmi3/ModelObserver.fmu",
                 "harness/py.typed", "harness/lib/libsto_native.so"):
        assert name in names


def test_every_imported_distribution_is_declared(wheel):
    """Requires-Dist of the wheel names every third-party distribution harness/ imports."""
    metadata = next(n for n in zipfile.ZipFile(wheel).namelist() if n.endswith("METADATA"))
    text = zipfile.ZipFile(wheel).read(metadata).decode()
    declared = {re.split(r"[ ;<>=!~\[]", line.split(":", 1)[1].strip())[0].lower()
                for line in text.splitlines() if line.startswith("Requires-Dist:")}
    imported = set()
    for path in (REPO / "harness").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                imported |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                imported.add(node.module.split(".")[0])
    owners = packages_distributions()
    needed = {owners[m][0].lower() for m in imported
              if m in owners and m not in sys.stdlib_module_names}
    assert needed - {"sto-harness"} <= declared, f"undeclared: {needed - declared}"


def test_the_installed_command_runs_from_another_folder(installed, tmp_path):
    command = installed / "bin" / "sto-harness"
    result = subprocess.run([str(command), "--help"], cwd=tmp_path, capture_output=True,
                            text=True, env=_clean_env())
    assert result.returncode == 0 and "identify" in result.stdout
    # a tiny identification with the FMUs installed in the package
    t = np.arange(2000) * 1e-3
    data = tmp_path / "log.csv"
    np.savetxt(data, np.column_stack([t, 0.1 * np.sin(3 * t), np.cos(2 * t)]), delimiter=",",
               header="time,theta,tau", comments="")
    result = subprocess.run([str(command), "identify", "log.csv", "--out", "est",
                             "--columns", "y=theta,u=tau", "--identifier", "off"],
                            cwd=tmp_path, capture_output=True, text=True, env=_clean_env())
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "est" / "estimates.csv").exists()
    where = subprocess.run([str(installed / "bin" / "python"), "-c",
                            "import harness.paths; print(harness.paths.default_fmu_dir())"],
                           cwd=tmp_path, capture_output=True, text=True, env=_clean_env())
    assert Path(where.stdout.strip()).is_relative_to(installed)


def test_the_installed_package_loads_its_native_library(installed, tmp_path):
    """The observer path of identify --robot (harness.robot.native) from the installed
    package alone: the library pip built at install time, no compiler at import."""
    script = ("import numpy as np, harness.robot.native as rn, harness.native_library as nl\n"
              "t = np.arange(3000) * 1e-3\n"
              "v = rn.observe_adaptive(np.sin(2 * t)[:, None], 1e-3, 5.0).velocity\n"
              "print(nl.library_path())\n"
              "print(np.max(np.abs(v[1000:, 0] - 2 * np.cos(2 * t[1000:]))))\n")
    env = {**_clean_env(), "PATH": "/nonexistent", "CC": "/nonexistent/cc"}
    result = subprocess.run([str(installed / "bin" / "python"), "-c", script], cwd=tmp_path,
                            capture_output=True, text=True, env=env)
    assert result.returncode == 0, result.stderr
    library, error = result.stdout.split()
    assert Path(library).is_relative_to(installed)
    assert float(error) < 1e-5  # measured 2.7e-6 (velocity of sin 2t, after 1 s)
