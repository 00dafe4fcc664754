"""The derivative pipeline chosen by the log itself: blocked cross-validation.

Each candidate is a zero-phase pipeline (:class:`harness.model.zero_phase.ZeroPhase`): a
Butterworth cut-off from a hundredth of the sample rate up to 0.8 of the Nyquist
frequency, with or without the benchmark's decimation by 10, and the cut-off that the
positions' noise floor suggests (:func:`harness.model.zero_phase.cutoff_for`); for a
model with Coulomb terms, each also with its friction rows. The log is
cut into FOLDS contiguous blocks; for each block, a candidate's least squares are fitted
on the rows outside it (a guard of the filter's border on either side), and scored on it
by simulation: short runs of the model, each from the measured state, driven by the
measured input (:class:`harness.model.scores.PieceSimulator`), and by the input it
reconstructs on the block through one reference pipeline
(:class:`harness.model.held_out_inputs.HeldOutInputs`). Neither score shares anything with
the candidate's filter, so a pipeline cannot win by smoothing away what it fails to
explain. Each sees what the other misses (the runs: a cut-off below a resonance; the
input: an inertia or a friction level off, which coarse positions hide from the runs), so
the candidates whose product of the two scores (each relative to the best candidate's) is
as good as the lowest (:func:`harness.model.as_good.as_good`) are kept, and of them the
one of the best simulation score is chosen; all scores are reported.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from .as_good import CLASS_TOLERANCE, as_good
from .fit import estimate
from .held_out_inputs import HeldOutInputs
from .log import LogFileError, ModelLog
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
    """One pipeline and its cross-validation scores (means over the blocks: ``score``, of
    the runs' relative position error; ``input_score``, of the input reconstruction's
    error relative to the reference's own; inf when it cannot be fitted or scored) and
    ``combined``, their product relative to the best of each (what the choice minimizes)."""

    settings: ZeroPhase
    score: float
    label: str
    input_score: float = math.nan   # nan: not scored (no reference pipeline for the log)
    combined: float = math.nan

    def as_dict(self) -> dict[str, object]:
        return {"label": self.label, "cutoff_hz": self.settings.cutoff,
                "decimation": self.settings.decimation,
                "differentiator": self.settings.differentiator,
                "friction_rows": self.settings.friction_rows,
                "score": _number(self.score), "input_score": _number(self.input_score),
                "combined": _number(self.combined)}


def _number(x: float) -> float | None:
    return x if math.isfinite(x) else None


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


def candidates(model: Model, log: ModelLog) -> list[tuple[str, ZeroPhase]]:
    """The pipelines tried on a log (labels and settings); for a model with Coulomb terms
    each also with its friction rows (:func:`harness.model.zero_phase.friction_mask`)."""
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
    if any(model.coulomb_coordinates):
        out += [(f"{label}, friction rows", dataclasses.replace(settings, friction_rows=True))
                for label, settings in out]
    return out


@dataclass(frozen=True)
class Trial:
    """A candidate of the cross-validation: regressor rows, the filter's border (the
    guard around a held-out block), and which unknowns are free (the others are 0)."""

    rows: Regression
    border: int
    free: np.ndarray


class CrossValidation:
    """Blocked cross-validation of least-squares estimates on a log: FOLDS contiguous
    blocks, each scored by simulation runs from the measured state."""

    def __init__(self, model: Model, log: ModelLog) -> None:
        self.model, self.log = model, log
        self.dynamics = Dynamics(model)
        length = int(np.clip(round(RUN_SECONDS / log.step), *RUN_SAMPLES))
        self.length = min(length, log.samples // (2 * FOLDS))
        self.edges = np.linspace(0, log.samples, FOLDS + 1).round().astype(int)
        blocks = [pieces(int(a), int(b), self.length, RUNS_PER_BLOCK)
                  for a, b in zip(self.edges, self.edges[1:])]
        self.runs = Pieces(np.concatenate([b.starts for b in blocks]), self.length)
        self.owner = np.concatenate([np.full(len(b.starts), k) for k, b in enumerate(blocks)])
        self.blocks: dict[str, np.ndarray] = {}   # each trial's score per block
        self.folds: dict[str, np.ndarray] = {}    # each trial's estimate per block

    @property
    def method(self) -> str:
        return (f"blocked cross-validation, {FOLDS} blocks, simulation runs of {self.length} "
                "samples from the measured state")

    def scores(self, trials: dict[str, Trial]) -> dict[str, float]:
        """Per trial, the mean over the blocks of its held-out runs' relative error (inf:
        it cannot be fitted or simulated); trials of one sub-step count run at once."""
        out: dict[str, float] = {}
        groups: dict[int, dict[str, np.ndarray]] = {}
        for label, trial in trials.items():
            try:
                full = _estimate(self.model, trial.rows, trial.free, slice(None))
            except (np.linalg.LinAlgError, ValueError):
                out[label] = math.inf
                continue
            self.folds[label] = self._fold_estimates(trial)
            groups.setdefault(_parts(self.dynamics, self.log, full), {})[label] = \
                self.folds[label]
        for parts, group in groups.items():
            blocks = _block_scores(self.dynamics, self.log, self.runs, parts, self.owner, group)
            self.blocks.update(blocks)
            for label, values in blocks.items():
                value = float(np.mean(values))
                out[label] = value if math.isfinite(value) else math.inf
        return {label: out[label] for label in trials}

    def _fold_estimates(self, trial: Trial) -> np.ndarray:
        """Per block, the estimate from the rows outside it (NaN where too few remain)."""
        log, rows = self.log, trial.rows
        out = np.full((len(self.edges) - 1, len(self.model.parameters)), np.nan)
        for k, (a, b) in enumerate(zip(self.edges, self.edges[1:])):
            lo = log.t[0] + (a - trial.border) * log.step
            hi = log.t[0] + (b + trial.border) * log.step
            train = (rows.t < lo) | (rows.t > hi)
            if train.sum() * rows.Y.shape[1] > int(trial.free.sum()):
                try:
                    out[k] = _estimate(self.model, rows, trial.free, train)
                except np.linalg.LinAlgError:
                    pass
        return out


def _estimate(model: Model, rows: Regression, free: np.ndarray, take) -> np.ndarray:
    """Least squares over the rows ``take`` with the unknowns outside ``free`` at 0."""
    theta = np.zeros(len(model.parameters))
    mask = None if rows.mask is None else rows.mask[take]
    lower, upper = model.bounds
    theta[free] = estimate(rows.Y[take][:, :, free], rows.r[take], model.nominal[free],
                           mask=mask, bounds=(lower[free], upper[free]))
    return theta


def choose_pipeline(model: Model, log: ModelLog) -> Choice:
    """The candidate pipeline of the best blocked cross-validated scores: among the
    candidates whose product of simulation and input scores (each relative to the best
    candidate's) is as good as the lowest product (:func:`as_good`, over the blocks), the
    one of the best simulation score (the simulation score alone when the log is too short
    for the reference pipeline). The log must be long enough for the noise-floor pipeline
    (LogFileError). A log on which no candidate can be fitted and simulated keeps the
    noise-floor pipeline, and says so in ``method``."""
    fallback = ZeroPhase.for_log(log)
    check_length(model, log, fallback)
    tried = [(label, settings) for label, settings in candidates(model, log)
             if log.samples >= minimum_samples(settings, len(model.parameters))
             and log.samples // FOLDS > 4 * settings.border]
    every = np.ones(len(model.parameters), dtype=bool)
    cv = CrossValidation(model, log)
    scores = cv.scores({label: Trial(regression(model, log, settings), settings.border, every)
                        for label, settings in tried})
    labels = [label for label, _ in tried]
    runs = {label: cv.blocks.get(label, np.full(FOLDS, np.inf)) for label in labels}
    reference, inputs = _input_scores(model, log, cv, labels)
    combined = combined_scores(runs, inputs)
    scored = [Candidate(settings, scores[label], label,
                        _mean(inputs[label]) if label in inputs else math.nan,
                        float(np.mean(combined[label]))) for label, settings in tried]
    label = pick(runs, combined)
    if label is None:
        return Choice(fallback, tuple(scored), "not cross-validated (no candidate's model can "
                      "be fitted and stays finite in simulation on the held-out blocks)",
                      power_above(model, log, fallback))
    best = next(c for c in scored if c.label == label)
    method = cv.method + (f", and the input reconstructed on them through the spectral "
                          f"pipeline at the noise floor ({reference:.4g} Hz); of the "
                          "candidates whose product of the two scores (each relative to the "
                          "best) is as good as the lowest, the best simulation score"
                          if reference is not None else "")
    return Choice(best.settings, tuple(scored), method, power_above(model, log, best.settings))


def _input_scores(model: Model, log: ModelLog, cv: CrossValidation, labels: list[str]
                  ) -> tuple[float | None, dict[str, np.ndarray]]:
    """The reference pipeline's cut-off and, per candidate, its held-out input score per
    block; (None, {}) when the log is too short for the reference."""
    try:
        reference = HeldOutInputs(model, log, cv.edges)
    except (LogFileError, np.linalg.LinAlgError, ValueError):
        return None, {}
    return reference.settings.cutoff, {
        label: reference.scores(cv.folds[label]) if label in cv.folds
        else np.full(FOLDS, np.inf) for label in labels}


def combined_scores(runs: dict[str, np.ndarray], inputs: dict[str, np.ndarray]
                    ) -> dict[str, np.ndarray]:
    """Per candidate and block, its simulation score times its input score, each over the
    best candidate's mean (the simulation score's ratio alone without input scores, and
    in a block without one: NaN, the reference keeps no row there)."""
    def ratios(scores: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        means = [_mean(v) for v in scores.values()]
        finite = [m for m in means if math.isfinite(m) and m > 0]
        least = min(finite) if finite else math.nan
        return {label: v / least for label, v in scores.items()}
    product = ratios(runs)
    if inputs:
        relative = ratios(inputs)
        product = {label: v * np.where(np.isnan(relative[label]), 1.0, relative[label])
                   for label, v in product.items()}
    return {label: np.where(np.isfinite(v), v, np.inf) for label, v in product.items()}


def _mean(scores: np.ndarray) -> float:
    """The mean of a candidate's block scores over the blocks that have one."""
    scored = scores[~np.isnan(scores)]
    return float(np.mean(scored)) if len(scored) else math.nan


def pick(runs: dict[str, np.ndarray], combined: dict[str, np.ndarray]) -> str | None:
    """The candidate chosen from its block scores: of those whose combined score is as
    good as the lowest (:func:`as_good`), the one of the best mean simulation score; None
    when no candidate has finite scores. Within the blocks' noise of the lowest product
    the simulation decides, as it did alone (on EMPS every candidate reconstructs the
    input within 2 % of the others)."""
    finite = [label for label, v in combined.items() if np.all(np.isfinite(v))]
    if not finite:
        return None
    lowest = combined[min(finite, key=lambda label: float(np.mean(combined[label])))]
    return min((label for label in finite if as_good(combined[label], lowest)),
               key=lambda label: float(np.mean(runs[label])))


@dataclass(frozen=True)
class ClassChoice:
    """The unknowns kept (``free``), the optional ones left out, every class scored
    (by the names it leaves out) and what leaving each optional unknown out alone costs
    (relative change of the cross-validated error, from the full class)."""

    free: np.ndarray
    left_out: tuple[str, ...]
    scores: dict[str, float]
    absence_costs: dict[str, float]
    not_excited: tuple[str, ...] = ()   # left out before the scoring: the log cannot tell

    def as_dict(self) -> dict[str, object]:
        return {"left_out": list(self.left_out), "not_excited": list(self.not_excited),
                "scores": {k: (v if math.isfinite(v) else None) for k, v in self.scores.items()},
                "absence_costs": {k: (v if math.isfinite(v) else None)
                                  for k, v in self.absence_costs.items()},
                "rule": f"the fewest unknowns within {100 * CLASS_TOLERANCE:g} % or one "
                        "standard error of the best cross-validated error (backward "
                        "elimination of optional unknowns)"}


def choose_class(model: Model, log: ModelLog, rows: Regression, border: int,
                 excitation: np.ndarray, too_weak: float) -> ClassChoice:
    """The model class among the parameters marked optional: backward elimination by the
    blocked cross-validation on ``rows``; an optional unknown whose excitation is below
    ``too_weak`` is left out first (the log cannot determine it)."""
    names = [p.name for p in model.parameters]
    optional = [k for k, p in enumerate(model.parameters) if p.optional]
    free = np.ones(len(names), dtype=bool)
    free[[k for k in optional if excitation[k] < too_weak]] = False

    def label(mask: np.ndarray) -> str:
        out = [names[k] for k in optional if not mask[k]]
        return "without " + ", ".join(out) if out else "every unknown"

    cv = CrossValidation(model, log)
    scores = cv.scores({label(free): Trial(rows, border, free)})
    current = free.copy()
    costs: dict[str, float] = {}
    while True:
        trials = {}
        for k in optional:
            if current[k]:
                mask = current.copy()
                mask[k] = False
                trials[label(mask)] = Trial(rows, border, mask)
        if not trials:
            break
        found = cv.scores(trials)
        scores.update(found)
        if not costs:  # the first round: each optional unknown's absence from the full class
            base = scores[label(current)]
            costs = {names[k]: found[label(_without(current, k))] / base - 1.0
                     for k in optional if current[k]}
        best = min(scores, key=lambda key: scores[key])
        step = min(found, key=lambda key: found[key])
        if not as_good(cv.blocks[step], cv.blocks[best]):
            break
        current = trials[step].free
    weak = tuple(names[k] for k in optional if excitation[k] < too_weak)
    return ClassChoice(current, tuple(names[k] for k in optional if not current[k]), scores,
                       costs, weak)


def _without(mask: np.ndarray, k: int) -> np.ndarray:
    out = mask.copy()
    out[k] = False
    return out


def _parts(dynamics: Dynamics, log: ModelLog, theta: np.ndarray) -> int:
    try:
        return parts_for(dynamics, log, theta)
    except (FloatingPointError, ValueError):
        return 1


def _block_scores(dynamics: Dynamics, log: ModelLog, runs: Pieces, parts: int,
                  owner: np.ndarray, folds: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per candidate, each block's held-out runs' relative error (inf for a candidate
    without an estimate in every block); the candidates' runs simulated at once."""
    usable = {label: theta for label, theta in folds.items() if np.all(np.isfinite(theta))}
    blocks = np.unique(owner)
    out = {label: np.full(len(blocks), np.inf) for label in folds if label not in usable}
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
            out[label] = np.array([
                np.sqrt(np.mean((np.sqrt(np.mean(mine[owner == k] ** 2, axis=(0, 1)))
                                 / simulator.motion) ** 2)) for k in blocks])
    return {label: np.where(np.isfinite(v), v, np.inf) for label, v in out.items()}


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
