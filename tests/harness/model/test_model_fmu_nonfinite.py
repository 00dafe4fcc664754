"""The model file's FMU fed finite inputs its equations cannot take (sqrt of a negative
position, inputs near 1e200): the internal step flags the first non-finite velocity,
equation entry or identifier sum, and the communication point reports it as an error with
its message, instead of returning OK while the identifier holds NaN."""
from __future__ import annotations

from pathlib import Path

import fmpy
import numpy as np
import pytest
from cli_runner import FMU_DIR, cli
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

MODEL = '''[model]
coordinates = ["x"]
inputs = ["F"]
equations = ["{eq}"]

[parameters]
M = {{ nominal = 2 }}
Fv = {{ nominal = 0.5 }}
'''


def export(tmp_path: Path, eq: str) -> Path:
    path = tmp_path / "m.toml"
    path.write_text(MODEL.format(eq=eq), encoding="utf-8")
    code, text = cli(["fmu", "--model", str(path), "--out", str(tmp_path / "out")])
    assert code == 0, text
    return tmp_path / "out" / "m.fmu"


def drive(fmu: Path, position, force, seconds: float = 4.0) -> tuple[float | None, list]:
    """doSteps of 0.01 s with the inputs of time t; the time of the first doStep that
    fails (None: none did) and the values of the outputs before it."""
    description = fmpy.read_model_description(str(fmu))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    slave = FMU2Slave(guid=description.guid, unzipDirectory=fmpy.extract(str(fmu)),
                      modelIdentifier="ModelObserver", instanceName="nonfinite")
    slave.instantiate(loggingOn=True)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.setReal([refs["observer.h"]], [1e-3])
        slave.enterInitializationMode()
        slave.setReal([refs["x"], refs["F"]], [position(0.0), force(0.0)])
        slave.exitInitializationMode()
        outputs = []
        for k in range(int(seconds / 0.01)):
            t = k * 0.01
            slave.setReal([refs["x"], refs["F"]], [position(t), force(t)])
            try:
                slave.doStep(currentCommunicationPoint=t, communicationStepSize=0.01)
            except FMICallException:
                return t, outputs
            outputs.append(slave.getReal([refs["M"], refs["Fv"], refs["der(x)"]]))
        return None, outputs
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("eq, position, force, words", [
    ("M*der(x,2) + Fv*sqrt(x)*der(x) = F", lambda t: -1.0 - 0.5 * np.sin(3 * t),
     lambda t: np.sin(2 * t), ["equation 1", "non-finite"]),
    ("M*der(x,2) + Fv*der(x) = F", lambda t: 0.3 * np.sin(3 * t),
     lambda t: 1e200 * np.sin(2 * t), ["overflowed", "scaling"]),
])
def test_a_non_finite_state_is_an_error_of_the_step_not_a_silent_nan(tmp_path, capfd, eq,
                                                                     position, force, words):
    failed_at, outputs = drive(export(tmp_path, eq), position, force)
    text = capfd.readouterr().out
    assert failed_at is not None, f"every doStep returned OK; outputs {outputs[-1:]}"
    assert all(np.all(np.isfinite(o)) for o in outputs)  # nothing non-finite published
    for word in words:
        assert word in text, text[-2000:]


def test_a_model_its_log_fits_runs_without_the_error(tmp_path):
    failed_at, outputs = drive(export(tmp_path, "M*der(x,2) + Fv*sqrt(x)*der(x) = F"),
                               lambda t: 1.5 + 0.5 * np.sin(3 * t), lambda t: np.sin(2 * t))
    assert failed_at is None and np.all(np.isfinite(outputs[-1]))


assert FMU_DIR  # the FMUs of this build (or the sanitized ones under sanitize.sh)
