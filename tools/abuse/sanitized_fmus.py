"""pytest plugin (``-p sanitized_fmus``, with tools/abuse on PYTHONPATH) for
tools/abuse/sanitize.sh: points every FMU fixture of tests/conftest.py at the
FMUs in $STO_FMU_DIR (the tests in tests/abuse read that variable themselves),
and keeps the sanitizer runtime out of the processes that the tests start
(compilers, fmpy compile): it is preloaded into this Python process only."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

DIRECTORY = Path(os.environ["STO_FMU_DIR"]).resolve()
os.environ.pop("LD_PRELOAD", None)


def _redirect(module) -> None:
    if getattr(module, "FMU_DIR", None) is not None and hasattr(module, "fmu_path"):
        module.FMU_DIR = DIRECTORY


def pytest_plugin_registered(plugin, manager):
    _redirect(plugin)


@pytest.hookimpl(trylast=True)
def pytest_sessionstart(session):
    for plugin in session.config.pluginmanager.get_plugins():
        _redirect(plugin)
    missing = [m for m in ("SuperTwistingObserver", "Pendulum", "TwistingController")
               if not (DIRECTORY / f"{m}.fmu").exists()]
    if missing:
        raise pytest.UsageError(f"{DIRECTORY} lacks {missing}: run tools/abuse/sanitize.sh")


def pytest_report_header(config):
    return f"sanitized FMUs from {DIRECTORY}"
