"""The generators of the results documents (docs/benchmarks.md lists each command and where
its report lands, under build/reports/ by default) and the helpers they share: realdata/
(pendulum plant data, sensors, methods, scores), robot_trajectories (the robots' exciting
closed-loop runs), robot_observer_methods (the model-based observer as a method)."""
