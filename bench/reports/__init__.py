"""The generators of the results documents (docs/benchmarks.md lists each command and where
its report lands, under build/reports/ by default) and the helpers they share: realdata/
(pendulum plant data, sensors, methods, scores), robot_trajectories (the robots' exciting
closed-loop runs), robot_observer_methods (the model-based observer as a method)."""
from __future__ import annotations

import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
REPORTS = REPO / "build" / "reports"
"""Where the generators write their documents and figures unless given --out."""


def commit() -> str:
    """The checkout's commit for a report's header (``-dirty`` with local changes)."""
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty", "--abbrev=10"],
                              cwd=REPO, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
