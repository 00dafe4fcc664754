"""fmpy harness for the observer/identifier FMUs: the paper's closed loops, recorded
logs, serial robots and model files, from a script or the ``sto-harness`` command.

The few functions a script needs are importable from here (fmpy style); each is
loaded on first use, so ``import harness`` stays cheap:

- closed loops: ``SCENARIOS``, ``run_scenario(scenario, fmu_dir)``, ``score``, and
  ``default_fmu_dir()`` (the FMUs installed with the package, or a checkout's build);
- recorded logs through the observer FMU: ``identify_file(path, fmu, parameters)``;
- sweeps: ``load_spec(path)``, ``run_sweep(spec, out)``;
- model files: ``read_model(path)`` (``ModelFileError`` for a bad file),
  ``build_fmu(model, path)`` (its observer/identifier FMU);
- serial robots: ``read_urdf(path)``, ``read_log(path, n)``, ``identify_robot(robot, log)``,
  ``fmu_parameters(robot)`` (the RobotObserver FMU's parameters).

Underneath: `harness.master` (the co-simulation master), `harness.fmus` (FMU access),
`harness.plots`, `harness.tables`, `harness.outputs` (atomic output folders). FMU log
lines of status Warning and worse go to the logging module (logger ``harness.fmu``);
see `harness.messages`.
"""
from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

# name -> the module that defines it
_EXPORTS = {
    "SCENARIOS": "harness.scenarios",
    "run_scenario": "harness.scenarios",
    "score": "harness.metrics",
    "default_fmu_dir": "harness.paths",
    "identify_file": "harness.identify",
    "load_spec": "harness.sweep.plan",
    "run_sweep": "harness.sweep",
    "read_model": "harness.model",
    "ModelFileError": "harness.model",
    "build_fmu": "harness.model.fmu_export",
    "read_urdf": "harness.robot.urdf",
    "read_log": "harness.robot.joint_log",
    "identify_robot": "harness.robot.pipeline",
    "fmu_parameters": "harness.robot.fmu",
}
__all__ = [
    "SCENARIOS", "ModelFileError", "build_fmu", "default_fmu_dir", "fmu_parameters",
    "identify_file", "identify_robot", "load_spec", "read_log", "read_model", "read_urdf",
    "run_scenario", "run_sweep", "score",
]

if TYPE_CHECKING:
    from harness.identify import identify_file
    from harness.metrics import score
    from harness.model import ModelFileError, read_model
    from harness.model.fmu_export import build_fmu
    from harness.paths import default_fmu_dir
    from harness.robot.fmu import fmu_parameters
    from harness.robot.joint_log import read_log
    from harness.robot.pipeline import identify_robot
    from harness.robot.urdf import read_urdf
    from harness.scenarios import SCENARIOS, run_scenario
    from harness.sweep import run_sweep
    from harness.sweep.plan import load_spec


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module 'harness' has no attribute {name!r}")
    value = getattr(import_module(_EXPORTS[name]), name)
    globals()[name] = value  # the next access is a plain lookup
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
