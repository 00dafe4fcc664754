"""fmpy harness for the SuperTwistingObserver FMU and its closed-loop bench.

Installed with the package: the three FMUs (``harness.paths.default_fmu_dir()``),
the ``sto-harness`` command (``python -m harness``) and this Python API:

- `harness.scenarios`: the paper's section 6 examples as closed-loop scenarios
  (``SCENARIOS``, ``run_scenario``), scored by `harness.metrics.score`;
- `harness.identify`: a recorded log through the observer (``identify`` in memory,
  ``identify_file`` streaming a CSV of any length), read by `harness.recording`;
- `harness.compare`: the paper's method against the FMU's defaults;
- `harness.sweep`: parameter and noise sweeps on Dask (its parts: `harness.sweep_plan`
  the spec and its runs, `harness.sweep_simulation` one run, `harness.sweep_dask` the
  cluster, `harness.sweep_table` the results, `harness.sweep_report` summary and figures);
- `harness.ssp`: the closed loop as an SSP file for other tools;
- `harness.master` and `harness.fmus`: the co-simulation master and FMU access
  underneath; `harness.plots`: the figures; `harness.tables`: the CSV files.

FMU log lines of status Warning and worse go to the logging module (logger
``harness.fmu``); see `harness.messages`.
"""
