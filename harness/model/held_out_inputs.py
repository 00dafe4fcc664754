"""The cross-validation's second score: how well each candidate's held-out estimate
reconstructs the input of its block, all candidates through one reference pipeline.

The short simulation runs (:class:`harness.model.scores.PieceSimulator`) see a model's
dynamics over a fraction of a second from a fitted initial state: they tell a cut-off below
a resonance, but on coarse positions (encoder steps) the steps dominate their error and
an inertia 10 % off barely shows (the two-link arm of bench/cases/two_link.py: 2.6 % for
a 20 Hz pipeline whose joint-1 torque is 10 % off, 2.8 % for a 4 Hz one at 3.6 %). The
input reconstruction sees such an error directly. Its reference is the same for every
candidate, so that no candidate is scored through its own filter: the spectral pipeline
at the noise-floor cut-off (:func:`harness.model.zero_phase.cutoff_for`), at every
sample, with its friction rows for a model with Coulomb terms where they leave enough of
the log (REFERENCE_ROWS).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .fit import fit
from .log import ModelLog
from .model import Model
from .zero_phase import Regression, ZeroPhase, cutoff_for, regression

#: The reference keeps its friction rows when they leave at least this share of each
#: equation's rows. Their margin around a reversal grows as the cut-off falls: on a
#: coarse log whose noise floor is low (the two-link arm's 0.01 rad encoder, 3.2 Hz) and
#: whose passive joint reverses often, they kept 1 % of the driven joint's rows, and that
#: reference's own estimate shrank every inertia of the passive joint towards zero.
REFERENCE_ROWS = 0.25


class HeldOutInputs:
    """The reference rows of a log cut into blocks (``edges``, sample indices): per block,
    the RMS of each equation's residual relative to the reference's own least-squares
    residual over the whole log (its yardstick: equations in any unit, and an input that
    is zero such as a passive joint's, count alike), pooled over the equations."""

    def __init__(self, model: Model, log: ModelLog, edges: np.ndarray) -> None:
        settings, rows = _reference(model, log)
        self.Y, self.r = rows.Y, rows.r
        self.mask = np.ones(rows.r.shape, dtype=bool) if rows.mask is None else rows.mask
        index = np.round((rows.t - log.t[0]) / log.step).astype(int)
        self.owner = np.searchsorted(edges, index, side="right") - 1
        self.blocks = len(edges) - 1
        own = fit(rows.Y, rows.r, model.nominal, mask=rows.mask, bounds=model.bounds).theta
        self.yardstick = self._rms(np.ones(len(self.r), dtype=bool), own)
        self.settings = settings

    def _rms(self, take: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Each equation's residual RMS over the reference rows ``take`` (its kept rows)."""
        mask = self.mask[take]
        with np.errstate(all="ignore"):  # an overflow scores inf: the candidate loses
            residual = (self.r[take] - self.Y[take] @ theta) * mask
            return np.sqrt(np.sum(residual ** 2, axis=0) / np.maximum(mask.sum(axis=0), 1))

    def scores(self, folds: np.ndarray) -> np.ndarray:
        """Per block, the relative input error of its estimate (``folds`` (blocks, p), each
        fitted outside the block) over the equations that keep rows in the block; inf for
        a block without an estimate, NaN for a block in which no equation keeps a row."""
        out = np.full(self.blocks, np.inf)
        empty = np.zeros(self.blocks, dtype=bool)
        yardstick = np.where(self.yardstick > 0, self.yardstick, 1.0)
        with np.errstate(all="ignore"):
            for k in range(self.blocks):
                take = self.owner == k
                kept = self.mask[take].any(axis=0)
                empty[k] = not kept.any()
                if not empty[k] and np.all(np.isfinite(folds[k])):
                    relative = self._rms(take, folds[k])[kept] / yardstick[kept]
                    out[k] = float(np.sqrt(np.mean(relative ** 2)))
        return np.where(empty, np.nan, np.where(np.isfinite(out), out, np.inf))


def _reference(model: Model, log: ModelLog) -> tuple[ZeroPhase, Regression]:
    """The reference pipeline and its rows: with friction rows for a model with Coulomb
    terms if they keep REFERENCE_ROWS of every equation's rows, else without."""
    settings = ZeroPhase.for_step(log.step, cutoff_for(log), 1, "spectral",
                                  friction_rows=any(model.coulomb_coordinates))
    rows = regression(model, log, settings)
    if rows.mask is not None and np.min(np.mean(rows.mask, axis=0)) < REFERENCE_ROWS:
        settings = dataclasses.replace(settings, friction_rows=False)
        rows = regression(model, log, settings)
    return settings, rows
