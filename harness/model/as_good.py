"""The one-standard-error rule of the blocked cross-validations (model files' pipelines
and classes, robots' joint terms): when is a candidate's score as good as the best's.

Plain numpy, so that the robot path does not load the model files' machinery (sympy)."""
from __future__ import annotations

import numpy as np

#: A model class that scores within this fraction of the best one scored, or within one
#: standard error of the blocks' differences from it, is as good: the one with fewer
#: unknowns is kept (the one-standard-error rule of cross-validation).
CLASS_TOLERANCE = 0.01


def as_good(candidate: np.ndarray, best: np.ndarray) -> bool:
    """Whether a class's block scores are as good as the best class's: its mean within
    CLASS_TOLERANCE of the best mean, or within one standard error of the paired block
    differences."""
    if not np.all(np.isfinite(candidate)):
        return False
    difference = candidate - best
    standard_error = float(np.std(difference, ddof=1) / np.sqrt(len(difference)))
    return float(np.mean(difference)) <= max(CLASS_TOLERANCE * float(np.mean(best)),
                                             standard_error)
