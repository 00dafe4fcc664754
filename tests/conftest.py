"""Shared fixtures: the FMUs that build.sh produced."""
from __future__ import annotations

import signal
from pathlib import Path

import pytest

from tools.fmu_models import models

# A shell without job control starts a command run in the background (`cmd &`) with
# SIGINT ignored, and the harness keeps an ignored SIGINT ignored (as under nohup): the
# Ctrl-C tests would then test nothing. Python's own handler here, and so the default
# disposition in every process the tests start.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

REPO = Path(__file__).resolve().parents[1]
FMU_DIR = REPO / "build" / "fmus"
FMI3_DIR = REPO / "build" / "fmi3"
MODEL_IDENTIFIERS = models()


def fmu_path(model_identifier: str, fmi_version: int = 2) -> Path:
    """Path of a built FMU; fails (never skips) with a hint if it is missing."""
    path = (FMU_DIR if fmi_version == 2 else FMI3_DIR) / f"{model_identifier}.fmu"
    if not path.exists():
        pytest.fail(f"{path} is missing: run ./build.sh fmus (./build.sh test builds it first)")
    return path


@pytest.fixture(scope="session")
def observer_fmu() -> Path:
    return fmu_path("SuperTwistingObserver")


@pytest.fixture(scope="session")
def pendulum_fmu() -> Path:
    return fmu_path("Pendulum")


@pytest.fixture(scope="session")
def controller_fmu() -> Path:
    return fmu_path("TwistingController")


@pytest.fixture(scope="session")
def robot_fmu() -> Path:
    return fmu_path("RobotObserver")


@pytest.fixture(scope="session", params=MODEL_IDENTIFIERS)
def fmi3_fmu(request) -> Path:
    """Each FMI 3.0 FMU in turn (build/fmi3/)."""
    return fmu_path(request.param, 3)


@pytest.fixture(scope="session")
def observer_fmi3() -> Path:
    return fmu_path("SuperTwistingObserver", 3)
