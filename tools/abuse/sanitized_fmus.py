"""pytest plugin (``-p tools.abuse.sanitized_fmus``, from the repository root) for
tools/abuse/sanitize.sh: points every FMU fixture of tests/conftest.py at the
FMUs in $STO_FMU_DIR (FMI 2) and $STO_FMI3_DIR (FMI 3) (the abuse tests read that variable themselves: abuse_fmi.fmu_dir, tests/cli_runner.py),
and keeps the sanitizer runtime out of the processes that the tests start
(compilers, fmpy compile): it is preloaded into this Python process only."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from tools.fmu_models import models

DIRECTORY = Path(os.environ["STO_FMU_DIR"]).resolve()
FMI3_DIRECTORY = Path(os.environ.get("STO_FMI3_DIR", DIRECTORY.parent / "fmi3")).resolve()
os.environ.pop("LD_PRELOAD", None)


def _redirect(module) -> None:
    if getattr(module, "FMU_DIR", None) is not None and hasattr(module, "fmu_path"):
        module.FMU_DIR = DIRECTORY
        if hasattr(module, "FMI3_DIR"):
            module.FMI3_DIR = FMI3_DIRECTORY


def pytest_plugin_registered(plugin, manager):
    _redirect(plugin)


@pytest.hookimpl(trylast=True)
def pytest_sessionstart(session):
    for plugin in session.config.pluginmanager.get_plugins():
        _redirect(plugin)
    missing = [str(d / f"{m}.fmu")
               for m in models()
               for d in (DIRECTORY, FMI3_DIRECTORY) if not (d / f"{m}.fmu").exists()]
    if missing:
        raise pytest.UsageError(f"{DIRECTORY} lacks {missing}: run tools/abuse/sanitize.sh")


def pytest_report_header(config):
    return f"sanitized FMUs from {DIRECTORY}"
