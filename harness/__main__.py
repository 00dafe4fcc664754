import atexit
import os
import signal
import sys

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
