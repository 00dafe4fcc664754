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
sample, with its friction rows for a model with Coulomb terms.
"""
from __future__ import annotations

import numpy as np

from .fit import fit
from .log import ModelLog
from .model import Model
from .zero_phase import ZeroPhase, cutoff_for, regression


class HeldOutInputs:
    """The reference rows of a log cut into blocks (``edges``, sample indices): per block,
    the RMS of each equation's residual relative to the reference's own least-squares
    residual over the whole log (its yardstick: equations in any unit, and an input that
    is zero such as a passive joint's, count alike), pooled over the equations."""

    def __init__(self, model: Model, log: ModelLog, edges: np.ndarray) -> None:
        settings = ZeroPhase.for_step(log.step, cutoff_for(log), 1, "spectral",
                                      friction_rows=any(model.coulomb_coordinates))
        rows = regression(model, log, settings)
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
        fitted outside the block); inf for a block without one."""
        out = np.full(self.blocks, np.inf)
        yardstick = np.where(self.yardstick > 0, self.yardstick, 1.0)
        with np.errstate(all="ignore"):
            for k in range(self.blocks):
                if np.all(np.isfinite(folds[k])):
                    relative = self._rms(self.owner == k, folds[k]) / yardstick
                    out[k] = float(np.sqrt(np.mean(relative ** 2)))
        return np.where(np.isfinite(out), out, np.inf)
