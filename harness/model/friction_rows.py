"""The equations in which Coulomb friction is what the model says: away from reversals.

A model's Coulomb term f_c sign(q') holds where the coordinate moves; near a reversal or
at low speed the friction is stiction, the Stribeck effect or a simulator's smoothing,
and a zero-phase filter mixes the torque of either side of a reversal where sign() of the
filtered velocity does not.  Those equations are left out of the least squares (the other
equations of the same sample stay): the rule of both identification paths, robots and
model files.
"""
from __future__ import annotations

import numpy as np


def friction_rows(velocity: np.ndarray, h: float, margin: float, min_speed: float,
                  slow_margin: float = 0.0, at: np.ndarray | None = None) -> np.ndarray:
    """(N, n) True for the equations of each coordinate (velocity (N, n) sampled every
    h s) whose friction is f_v q' + f_c sign(q'): further than ``margin`` s from its
    reversals and at |q'| >= min_speed, also over ``slow_margin`` s on both sides; at the
    samples ``at`` only (increasing indices; None: every sample), (len(at), n).

    Also where the coordinate slows down without reversing, which the reversal margin does
    not catch.  A filtered regression carries the friction of the filter's memory: its
    rows need the speed over that memory, slow_margin."""
    rows = [joint_friction_rows(velocity[:, i], h, margin, min_speed, slow_margin, at)
            for i in range(velocity.shape[1])]
    return (np.column_stack(rows) if rows else
            np.zeros((len(velocity) if at is None else len(at), 0), dtype=bool))


def joint_friction_rows(velocity: np.ndarray, h: float, margin: float, min_speed: float,
                        slow_margin: float = 0.0, at: np.ndarray | None = None
                        ) -> np.ndarray:
    """friction_rows of one coordinate: velocity (N,), the result (N,) or (len(at),)."""
    if not min_speed >= 0.0:
        raise ValueError(f"min_speed must be >= 0, not {min_speed!r}")
    at = np.arange(len(velocity)) if at is None else np.asarray(at)
    flips = np.flatnonzero(np.signbit(velocity[1:]) != np.signbit(velocity[:-1])) + 1
    slow = np.flatnonzero(np.abs(velocity) < min_speed)
    return ~_near(flips, at, h, max(margin, h)) & ~_near(slow, at, h, slow_margin)


def away_from_reversals(velocity: np.ndarray, h: float, margin: float) -> np.ndarray:
    """(N, n) True where each coordinate's velocity keeps its sign for ``margin`` s on both
    sides (friction_rows without a speed threshold)."""
    return friction_rows(velocity, h, margin, min_speed=0.0)


def _near(events: np.ndarray, at: np.ndarray, h: float, margin: float) -> np.ndarray:
    """True for each sample of ``at`` within +-margin s of one of the ``events`` (sample
    indices, increasing; margin 0: the sample itself is one)."""
    half = int(round(margin / h))
    return (np.searchsorted(events, at + half, side="right")
            > np.searchsorted(events, at - half, side="left"))
