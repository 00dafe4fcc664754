"""Abuse tools: sanitizer, valgrind and fuzz runs, the soak, and the raw FMI access
(abuse_fmi) shared by them and the abuse tests (tests/fmu, tests/cli_runner.py)."""
