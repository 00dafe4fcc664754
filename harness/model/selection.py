"""The derivative pipeline chosen by the log itself: blocked cross-validation.

Each candidate is a zero-phase pipeline (:class:`harness.model.zero_phase.ZeroPhase`): a
Butterworth cut-off from a hundredth of the sample rate up to 0.8 of the Nyquist
frequency, with or without the benchmark's decimation by 10, and the cut-off that the
positions' noise floor suggests (:func:`harness.model.zero_phase.cutoff_for`). The log is
cut into FOLDS contiguous blocks; for each block, a candidate's least squares are fitted
on the rows outside it (a guard of the filter's border on either side), and scored on it
by simulation: short runs of the model, each from the measured state, driven by the
measured input (:class:`harness.model.scores.PieceSimulator`). That score shares nothing
with the candidate's filter, so a pipeline cannot win by smoothing away what it fails to
explain. The candidate of the lowest mean score is chosen; all scores are reported.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from .fit import estimate
from .log import ModelLog
from .model import Model
from .scores import Pieces, PieceSimulator, parts_for, pieces
from .simulation import Dynamics
from .zero_phase import (
    DECIMATION,
    Regression,
    ZeroPhase,
    check_length,
    cutoff_for,
    minimum_samples,
    regression,
)

#: Cut-offs tried, as fractions of the sample rate (0.4: 0.8 of the Nyquist frequency),
#: with spectral derivatives ...
SPECTRAL_FRACTIONS = (0.02, 0.05, 0.1, 0.2, 0.4)
#: ... and with central differences.
CENTRAL_FRACTIONS = (0.1, 0.2)
#: The benchmark's pipeline (IDIM-LS): central differences at a tenth of the sample rate,
#: decimated by DECIMATION.
FOLDS = 5
#: A scoring run lasts this long [s], within RUN_SAMPLES samples ...
RUN_SECONDS = 0.2
RUN_SAMPLES = (40, 400)
#: ... and at most this many runs score a block.
RUNS_PER_BLOCK = 16
#: A chosen band that leaves more than this share of a coordinate's motion power above
#: it is reported.
POWER_ABOVE = 0.01


@dataclass(frozen=True)
class Candidate:
    """One pipeline and its cross-validation score (mean over the blocks of the runs'
    relative position error; inf when it cannot be fitted or scored)."""

    settings: ZeroPhase
    score: float
    label: str

    def as_dict(self) -> dict[str, object]:
        return {"label": self.label, "cutoff_hz": self.settings.cutoff,
                "decimation": self.settings.decimation,
                "differentiator": self.settings.differentiator,
                "score": self.score if math.isfinite(self.score) else None}


@dataclass(frozen=True)
class Choice:
    """The pipeline chosen for a log, every candidate's score, and how it was scored."""

    settings: ZeroPhase
    candidates: tuple[Candidate, ...]
    method: str
    power_above: dict[str, float]   # per coordinate: share of its motion power above the band

    def as_dict(self) -> dict[str, object]:
        return {"method": self.method, "chosen": self.settings.as_dict(),
                "candidates": [c.as_dict() for c in self.candidates],
                "power_above_cutoff": self.power_above}


def candidates(log: ModelLog) -> list[tuple[str, ZeroPhase]]:
    """The pipelines tried on a log (labels and settings)."""
    rate = 1.0 / log.step
    out = [(f"spectral, {f * rate:.4g} Hz", ZeroPhase.for_step(log.step, f * rate, 1, "spectral"))
           for f in SPECTRAL_FRACTIONS]
    out += [(f"central differences, {f * rate:.4g} Hz",
             ZeroPhase.for_step(log.step, f * rate, 1)) for f in CENTRAL_FRACTIONS]
    out.append((f"central differences, {0.1 * rate:.4g} Hz, decimated by {DECIMATION} (IDIM-LS)",
                ZeroPhase.for_step(log.step, 0.1 * rate, DECIMATION)))
    noise = cutoff_for(log)
    if not math.isclose(noise, 0.1 * rate, rel_tol=1e-6):
        out.append((f"central differences, {noise:.4g} Hz (noise floor), decimated by "
                    f"{DECIMATION}", ZeroPhase.for_step(log.step, noise, DECIMATION)))
    return out


def choose_pipeline(model: Model, log: ModelLog) -> Choice:
    """The candidate pipeline of the best blocked cross-validated simulation score. The
    log must be long enough for the noise-floor pipeline (LogFileError). A log on which no
    candidate can be fitted and simulated keeps the noise-floor pipeline, and says so in
    ``method``."""
    fallback = ZeroPhase.for_log(log)
    check_length(model, log, fallback)

    def kept(why: str) -> Choice:
        return Choice(fallback, (), f"not cross-validated ({why})",
                      power_above(model, log, fallback))

    dynamics = Dynamics(model)
    tried = [(label, settings) for label, settings in candidates(log)
             if log.samples >= minimum_samples(settings, len(model.parameters))
             and log.samples // FOLDS > 4 * settings.border]
    rows = {label: regression(model, log, settings) for label, settings in tried}
    full = {}
    for label, r in rows.items():
        try:
            full[label] = estimate(r.Y, r.r, model.nominal)
        except (np.linalg.LinAlgError, ValueError):
            continue
    tried = [(label, settings) for label, settings in tried if label in full]
    if not tried:
        return kept("no candidate pipeline can be fitted on this log")
    length = int(np.clip(round(RUN_SECONDS / log.step), *RUN_SAMPLES))
    length = min(length, log.samples // (2 * FOLDS))
    edges = np.linspace(0, log.samples, FOLDS + 1).round().astype(int)
    blocks = [pieces(int(a), int(b), length, RUNS_PER_BLOCK) for a, b in zip(edges, edges[1:])]
    runs = Pieces(np.concatenate([b.starts for b in blocks]), length)
    owner = np.concatenate([np.full(len(b.starts), k) for k, b in enumerate(blocks)])
    folds = {label: _fold_estimates(model, log, rows[label], edges, settings.border)
             for label, settings in tried}
    groups: dict[int, list[str]] = {}
    for label, _ in tried:  # candidates of one sub-step count are simulated together
        groups.setdefault(_parts(dynamics, log, full[label]), []).append(label)
    scores: dict[str, float] = {}
    for parts, labels in groups.items():
        scores.update(_scores(dynamics, log, runs, parts, owner,
                              {label: folds[label] for label in labels}))
    scored = [Candidate(settings, scores[label], label) for label, settings in tried]
    finite = [c for c in scored if math.isfinite(c.score)]
    if not finite:
        return kept("no candidate's model stays finite in simulation on the held-out blocks")
    best = min(finite, key=lambda c: c.score)
    return Choice(best.settings, tuple(scored),
                  f"blocked cross-validation, {FOLDS} blocks, simulation runs of {length} "
                  f"samples from the measured state", power_above(model, log, best.settings))


def _parts(dynamics: Dynamics, log: ModelLog, theta: np.ndarray) -> int:
    try:
        return parts_for(dynamics, log, theta)
    except (FloatingPointError, ValueError):
        return 1


def _fold_estimates(model: Model, log: ModelLog, rows: Regression, edges: np.ndarray,
                    border: int) -> np.ndarray:
    """Per block, the least-squares estimate from the rows outside it (guard: the filter's
    border each side); NaN where too few rows remain."""
    t0 = log.t[0]
    out = np.full((len(edges) - 1, len(model.parameters)), np.nan)
    for k, (a, b) in enumerate(zip(edges, edges[1:])):
        lo, hi = t0 + (a - border) * log.step, t0 + (b + border) * log.step
        train = (rows.t < lo) | (rows.t > hi)
        if train.sum() * rows.Y.shape[1] > len(model.parameters):
            try:
                out[k] = estimate(rows.Y[train], rows.r[train], model.nominal)
            except np.linalg.LinAlgError:
                pass
    return out


def _scores(dynamics: Dynamics, log: ModelLog, runs: Pieces, parts: int, owner: np.ndarray,
            folds: dict[str, np.ndarray]) -> dict[str, float]:
    """Per candidate, the mean over the blocks of its held-out runs' relative error (the
    candidates' runs simulated at once)."""
    usable = {label: theta for label, theta in folds.items() if np.all(np.isfinite(theta))}
    out = {label: math.inf for label in folds if label not in usable}
    if not usable:
        return out
    count = len(runs.starts)
    simulator = PieceSimulator(dynamics, log, Pieces(np.tile(runs.starts, len(usable)),
                                                     runs.length), parts)
    theta = np.concatenate([fold[owner] for fold in usable.values()])
    with np.errstate(all="ignore"):
        error = simulator.residuals(theta)
    for c, label in enumerate(usable):
        mine = error[c * count:(c + 1) * count]
        per_block = [np.sqrt(np.mean(mine[owner == k] ** 2, axis=(0, 1))) / simulator.motion
                     for k in np.unique(owner)]
        value = float(np.mean([np.sqrt(np.mean(b ** 2)) for b in per_block]))
        out[label] = value if math.isfinite(value) else math.inf
    return out


def power_above(model: Model, log: ModelLog, settings: ZeroPhase) -> dict[str, float]:
    """Per coordinate that moves, the share of its (detrended) power above the cut-off."""
    rate = 1.0 / log.step
    out: dict[str, float] = {}
    for i, name in enumerate(model.coordinates):
        q = log.q[:, i]
        if not np.ptp(q) > 0.0:
            continue
        f, power = scipy.signal.welch(q, fs=rate, nperseg=min(4096, max(16, len(q) // 4)),
                                      detrend="linear")
        total = float(power.sum())
        out[name] = float(power[f > settings.cutoff].sum() / total) if total > 0 else 0.0
    return out
