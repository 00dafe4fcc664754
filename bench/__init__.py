"""Benchmarks, run as modules from the repository root (not run by the tests):

- ``bench.reports``: the scripts that generate the results documents (into build/reports/);
- ``bench.perf``: cost and speed drivers (Python, and the C drivers CMake builds);
- ``bench.investigations``: scripts that answer one question each, cited by docs/design/.

Example: ``python -m bench.reports.real_measurements --quick``.
"""
