"""What the harness tells its user: FMU log lines and notes on stderr, counted.

Library code logs to the ``harness`` loggers (the FMUs' lines to
``harness.fmu``, see :mod:`harness.fmus`); Python users see WARNING and
above through the logging module (Python's last-resort handler prints them on
stderr when no handler is configured).  The command line installs
:class:`Console` for the duration of a command: a stderr handler (ERROR and
above only with ``--quiet``) that also counts the warnings, so that a command
can exit non-zero when its result cannot be trusted.
"""
from __future__ import annotations

import logging
import sys
from typing import TextIO

LOGGER = logging.getLogger("harness")


class Console(logging.Handler):
    """Prints ``harness`` log records on stderr and counts those of WARNING and above."""

    def __init__(self, quiet: bool = False, stream: TextIO | None = None):
        super().__init__(logging.DEBUG)
        self.quiet = quiet
        self.stream = stream
        self.warnings = 0
        self.errors = 0

    def emit(self, record: logging.LogRecord) -> None:
        if record.levelno >= logging.ERROR:
            self.errors += 1
        elif record.levelno >= logging.WARNING:
            self.warnings += 1
        else:
            return
        if self.quiet and record.levelno < logging.ERROR:
            return
        stream = self.stream or sys.stderr  # looked up now: tests redirect sys.stderr
        try:
            stream.write(f"harness: {record.levelname.lower()}: {record.getMessage()}\n")
            stream.flush()
        except (BrokenPipeError, ValueError):  # a closed stderr: nothing to tell
            pass

    def __enter__(self) -> Console:
        LOGGER.addHandler(self)
        self._level = LOGGER.level
        if LOGGER.getEffectiveLevel() > logging.WARNING:
            LOGGER.setLevel(logging.WARNING)
        self._propagate, LOGGER.propagate = LOGGER.propagate, False
        return self

    def __exit__(self, *exc) -> None:
        LOGGER.removeHandler(self)
        LOGGER.setLevel(self._level)
        LOGGER.propagate = self._propagate


def note(text: str) -> None:
    """A warning from the harness itself (not an FMU): shown and counted like one."""
    LOGGER.warning(text)
