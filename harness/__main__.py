import atexit
import os
import signal
import sys


def _quiet_interrupts(unraisable: "sys.UnraisableHookArgs") -> None:
    """A Ctrl-C that lands in a finalizer is dropped by Python with "Exception ignored"
    and a traceback; the output folder notes it and ends the command before its commit
    (harness.outputs), so it is not printed as an error here."""
    if not isinstance(unraisable.exc_value, KeyboardInterrupt):
        sys.__unraisablehook__(unraisable)


sys.unraisablehook = _quiet_interrupts
try:
    from .cli import main  # imports numpy and more: Ctrl-C may come while it loads
    status = main()
    # the command has finished (its outputs are complete): a Ctrl-C now would only
    # interrupt the interpreter's shutdown, dying by the signal instead of the status
    signal.signal(signal.SIGINT, signal.SIG_IGN)
except KeyboardInterrupt:  # before main could catch it: said, not a traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    print("\nharness: interrupted", file=sys.stderr)
    status = 130
if status in (130, 143):
    # Under "python -m", CPython exits by the signal (status -2) after a caught Ctrl-C
    # that ended code run by exec() of a string (sympy, dataclasses do), whatever the
    # status: the exit handlers are run and the streams flushed here, then the status.
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
sys.exit(status)
