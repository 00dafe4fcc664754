"""The robot's model class from its log: which extra joint terms (offset, armature,
asymmetric Coulomb friction; harness.robot.joint_terms) the data support.

Every combination of the three is fitted by the one least squares (harness.model.fit)
outside each of BLOCKS contiguous blocks of the regression's rows, with a guard of the
rows over which residuals are correlated, and scored on the held-out block: the RMS of
the predicted minus the measured torques over the RMS of the measured ones, over the
joint equations the regression uses. The class kept has the fewest terms among those
as good as the best (its mean within 1 % or one standard error of the paired block
differences, harness.model.as_good), the lower mean breaking a tie.

A class whose fit on the whole log puts a term that physics keeps >= 0 (an armature, a
Coulomb level) below zero by more than CONTRADICTED standard errors is not a candidate:
the log contradicts it (a torque that a negative rotor inertia would explain is some
other effect), and no physically consistent model of that class exists near its estimate.
"""
from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..log_signals import LogSignalsError
from ..model.as_good import as_good
from ..model.fit import estimate, fit
from .base_parameters import BaseParameters
from .joint_terms import OPTION_ITEMS, JointTerms, check_directions
from .layout import ParameterLayout

if TYPE_CHECKING:
    from .pipeline import Rows

#: Contiguous blocks of the cross-validation.
BLOCKS = 5
#: A term whose absence raises the best cross-validated error by more than this is named.
ABSENCE_REPORTED = 0.01
#: A term kept >= 0 by physics estimated below zero by more than this many standard
#: errors: the log contradicts the class.
CONTRADICTED = 3.0
#: Every class: each combination of the terms --joint-terms names.
CANDIDATES = tuple(JointTerms(**dict(zip(OPTION_ITEMS.values(), switches)))
                   for switches in itertools.product((False, True), repeat=len(OPTION_ITEMS)))


def label(terms: JointTerms) -> str:
    """The class as --joint-terms writes it ("none" for the core's model alone)."""
    items = [item for item, switch in OPTION_ITEMS.items() if getattr(terms, switch)]
    return ",".join(items) or "none"


@dataclass(frozen=True)
class TermsChoice:
    """The class kept and every class's cross-validated torque error (None: the class
    cannot be identified from this log, with the reason)."""

    terms: JointTerms
    scores: dict[str, float | None]
    reasons: dict[str, str]
    note: str | None = None  # why the classes were not compared (the core's model kept)

    def absence_costs(self) -> dict[str, float]:
        """Per term of the class kept, how much worse the class scores without it
        (relative; more than ABSENCE_REPORTED: the log needs the term)."""
        chosen = self.scores.get(label(self.terms))
        out = {}
        for item, switch in OPTION_ITEMS.items():
            if not getattr(self.terms, switch) or not chosen:
                continue
            without = self.scores.get(label(dataclasses.replace(self.terms, **{switch: False})))
            if without is not None:
                out[item] = without / chosen - 1.0
        return out

    def as_dict(self) -> dict[str, object]:
        return {"chosen": label(self.terms), "scores": self.scores, "refused": self.reasons,
                "absence_costs": self.absence_costs(), "note": self.note,
                "definition": f"mean over {BLOCKS} contiguous held-out blocks of the RMS of "
                              "(predicted - measured torque) over the RMS of the measured "
                              "torque, the model fitted outside each block",
                "rule": "the fewest terms within 1 % or one standard error of the best"}


def choose_joint_terms(rows: Rows, base_for: Callable[[JointTerms], BaseParameters],
                       nominal: np.ndarray, joint_names: list[str],
                       required: bool = True) -> TermsChoice:
    """The model class of CANDIDATES the log supports (see the module); ``base_for`` gives
    a class's base parameters, ``nominal`` the URDF's 12 n standard parameters.
    LogSignalsError if no class can be fitted on the blocks; unless ``required``, the
    core's model alone is kept instead, with a note that says why."""
    n = len(joint_names)
    blocks: dict[str, np.ndarray] = {}
    reasons: dict[str, str] = {}
    for terms in CANDIDATES:
        one_way = check_directions(terms, rows.speed, rows.mask, joint_names)
        if one_way is None:
            one_way = _contradicted(rows, base_for(terms), terms, nominal, joint_names)
        if one_way is not None:
            reasons[label(terms)] = one_way
            continue
        blocks[label(terms)] = _block_errors(rows, base_for(terms), terms, nominal, n)
    means = {key: float(np.mean(errors)) for key, errors in blocks.items()}
    finite = {key: value for key, value in means.items() if math.isfinite(value)}
    if not finite:
        why = "no model class can be fitted on this log's blocks (too few joint equations in each)"
        if required:
            raise LogSignalsError(f"--joint-terms auto: {why}; name the terms")
        return TermsChoice(JointTerms(), dict.fromkeys(map(label, CANDIDATES)), reasons,
                           f"{why}: the core's model alone (--joint-terms names the terms)")
    best = min(finite, key=lambda key: finite[key])
    by_label = {label(terms): terms for terms in CANDIDATES}
    good = [key for key in finite if as_good(blocks[key], blocks[best])]
    chosen = min(good, key=lambda key: (len(by_label[key].kinds), finite[key]))
    scores: dict[str, float | None] = {
        label(t): (means[label(t)] if math.isfinite(means.get(label(t), math.nan)) else None)
        for t in CANDIDATES}
    return TermsChoice(by_label[chosen], scores, reasons)


def _regression(rows: Rows, base: BaseParameters, terms: JointTerms, nominal: np.ndarray,
                n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The class's base regressor, the torques left to it and the URDF's base values."""
    from .pipeline import known_columns

    Y = rows.extend(terms)
    known = known_columns(n, base)
    z = rows.torque - Y[:, :, known] @ nominal[known]
    return base.regressor(Y), z, base.project(np.concatenate([nominal, np.zeros(terms.count(n))]))


def _contradicted(rows: Rows, base: BaseParameters, terms: JointTerms, nominal: np.ndarray,
                  joint_names: list[str]) -> str | None:
    """Why the log contradicts the class (a term kept >= 0 by physics, alone in its base
    parameter, estimated below -CONTRADICTED standard errors), or None."""
    n = len(joint_names)
    if not terms.kinds:
        return None
    start = ParameterLayout(n, len(terms.kinds)).standard_size
    signed = start + np.flatnonzero(terms.nonnegative(n))
    alone = [k for k, column in enumerate(base.base)
             if column in signed and not np.any(base.K[k])]
    if not alone:
        return None
    Yb, z, nominal_beta = _regression(rows, base, terms, nominal, n)
    try:
        result = fit(Yb, z, nominal_beta, batch=rows.correlation, mask=rows.mask)
    except (ValueError, np.linalg.LinAlgError):
        return None  # the blocks' fits say what cannot be fitted
    for k in alone:
        value, error = result.theta[k], result.std_error[k]
        if value < -CONTRADICTED * error:
            return (f"{base.names[k]} = {value:.4g} +- {error:.2g} is negative: the log "
                    f"contradicts it")
    return None


def _block_errors(rows: Rows, base: BaseParameters, terms: JointTerms, nominal: np.ndarray,
                  n: int) -> np.ndarray:
    """Each block's held-out relative torque error of the class ``terms``."""
    Yb, z, start = _regression(rows, base, terms, nominal, n)
    count = len(z)
    errors = np.full(BLOCKS, math.inf)
    for b, block in enumerate(np.array_split(np.arange(count), BLOCKS)):
        train = np.ones(count, dtype=bool)
        train[max(0, block[0] - rows.correlation):block[-1] + 1 + rows.correlation] = False
        try:
            beta = estimate(Yb[train], z[train], start, mask=rows.mask[train])
        except (ValueError, np.linalg.LinAlgError):
            continue
        held = rows.mask[block]
        measured = np.linalg.norm(rows.torque[block] * held)
        if measured > 0:
            error = (z[block] - Yb[block] @ beta) * held
            errors[b] = float(np.linalg.norm(error) / measured)
    return errors
