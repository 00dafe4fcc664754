"""Cost and speed drivers: the master loop, the observer's and the robot pipeline's step
(C drivers compiled by cmake/tools.cmake), sweeps on Dask, identify on long logs.
Figures and commands: docs/design/performance.md."""
