"""harness.messages: the command line's console prints the harness's warnings and errors
on stderr and counts them (a warning makes the exit status 1); --quiet keeps errors."""
from __future__ import annotations

import io
import logging

from harness.messages import LOGGER, Console, note


def test_warnings_and_errors_are_printed_and_counted():
    stream = io.StringIO()
    with Console(stream=stream) as console:
        note("the log is short")
        LOGGER.error("the FMU failed")
        LOGGER.info("not shown")
    assert console.warnings == 1 and console.errors == 1
    assert stream.getvalue() == ("harness: warning: the log is short\n"
                                 "harness: error: the FMU failed\n")


def test_quiet_prints_errors_only_but_counts_everything():
    stream = io.StringIO()
    with Console(quiet=True, stream=stream) as console:
        note("a warning")
        logging.getLogger("harness.fmu").error("an FMU's error")  # a child logger
    assert console.warnings == 1 and console.errors == 1
    assert stream.getvalue() == "harness: error: an FMU's error\n"


def test_the_logger_is_given_back_as_it_was():
    level, propagate, handlers = LOGGER.level, LOGGER.propagate, list(LOGGER.handlers)
    with Console(stream=io.StringIO()):
        assert not LOGGER.propagate
    assert (LOGGER.level, LOGGER.propagate, LOGGER.handlers) == (level, propagate, handlers)


def test_a_closed_stderr_is_not_an_error():
    stream = io.StringIO()
    stream.close()
    with Console(stream=stream) as console:
        note("nobody reads this")
    assert console.warnings == 1
