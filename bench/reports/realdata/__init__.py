"""Helpers of bench/reports/real_measurements.py: the observer FMU against classical baselines on
plant data that is not made by the observer's own discretization.

plants   -- the pendulum trajectories (open loop, closed loop; several integrators)
sensors  -- measurement corruption (noise, encoder quantization) and nominal-model errors
baselines -- Kalman filter, RTS smoother, Savitzky-Golay, least squares
methods  -- every method run on one data set, as comparable Estimate objects
scoring  -- the metrics
report   -- markdown tables and the figure
"""
