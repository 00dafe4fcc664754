"""The generators of the results documents (docs/benchmarks.md lists each command and where
its report lands, under build/reports/ by default) and the helpers they share: realdata/
(pendulum plant data, sensors, methods, scores), robot_trajectories (the robots' exciting
closed-loop runs), robot_observer_methods (the model-based observer as a method)."""
from __future__ import annotations

from pathlib import Path

REPORTS = Path(__file__).resolve().parents[2] / "build" / "reports"
"""Where the generators write their documents and figures unless given --out."""
