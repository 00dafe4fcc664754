"""How well the identification's models predict the training log, and which one is written.

Three models are scored on the equations the regression used (the joint equations of
the sampled rows that friction_rows kept; for the observer method, the filtered
equations): the URDF as given, the base-parameter estimate (least squares, not
necessarily physically consistent) and the physically consistent parameters.  The
score is validate's: the RMS of (predicted - measured torque) over the RMS of the
measured torque, per joint and pooled over the joints.

The consistent model is written unless it predicts worse than the URDF it started
from: then the URDF's values are kept (identified.urdf has the input's inertials and
friction) and a warning says so.  A consistent model more than CONSISTENT_MARGIN
(relative) worse than the estimate is written with a warning: the data and a physically
consistent model of this kinematic chain disagree.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .layout import ParameterLayout

CONSISTENT_MARGIN = 0.05  # relative: consistent error <= (1 + margin) * the estimate's
# ... or at most this much more (0.1 % of the torque): on an exact log both errors are
# rounding, whose ratio means nothing
CONSISTENT_FLOOR = 1e-3


@dataclass
class Prediction:
    """A model's relative torque prediction error on the training log."""

    pooled: float
    per_joint: dict[str, float | None]  # None: a joint whose measured torque is all 0

    def as_json(self) -> dict:
        return {"pooled": self.pooled, "per_joint": self.per_joint}


def prediction_error(predicted: np.ndarray, measured: np.ndarray, mask: np.ndarray,
                     names: list[str]) -> Prediction:
    """The relative error of predicted against measured torques (N, n) over the joint
    equations where mask (N, n) is True."""
    error = (predicted - measured) * mask
    measured = measured * mask
    per_joint: dict[str, float | None] = {}
    for i, name in enumerate(names):
        scale = float(np.linalg.norm(measured[:, i]))
        per_joint[name] = float(np.linalg.norm(error[:, i])) / scale if scale > 0 else None
    total = float(np.linalg.norm(measured))
    pooled = float(np.linalg.norm(error)) / total if total > 0 else float("inf")
    return Prediction(pooled, per_joint)


@dataclass
class Choice:
    """The parameters to write, the training-log scores and the warnings."""

    pi: np.ndarray
    written: str                                  # "consistent" or "urdf"
    predictions: dict[str, Prediction]            # "urdf", "estimate", "consistent"
    warnings: list[str] = field(default_factory=list)


#: A link mass this many times the URDF's (or a fraction of it) is named in a warning.
MASS_RATIO = 10.0


def implausible_masses(consistent: np.ndarray, nominal: np.ndarray,
                       link_names: list[str]) -> list[str]:
    """Warnings for the links whose identified mass is MASS_RATIO times the URDF's, or
    less than its MASS_RATIO-th: the data leave it to directions they hardly see."""
    out = []
    layout = ParameterLayout(len(link_names))
    for i, name in enumerate(link_names):
        mass, urdf = consistent[layout.mass(i)], nominal[layout.mass(i)]
        if urdf > 0 and not (urdf / MASS_RATIO <= mass <= MASS_RATIO * urdf):
            out.append(f"{name}'s identified mass {mass:.4g} kg is {mass / urdf:.3g} times the "
                       f"URDF's {urdf:.4g} kg: the log hardly determines it (a coarse encoder "
                       f"or a short --window lets the derivatives' noise decide; try a longer "
                       f"--window, or --unknown payload)")
    return out


def choose_model(predictions: dict[str, Prediction], consistent: np.ndarray,
                 nominal: np.ndarray, link_names: list[str] | None = None,
                 missing_terms: tuple[str, ...] = ()) -> Choice:
    """The consistent parameters, or the URDF's (nominal) if the consistent model
    predicts the training log worse than the URDF; warnings for both cases of the
    module's description.  predictions: "urdf", "estimate" and "consistent";
    missing_terms: joint terms the fitted class leaves out (the warning names them)."""
    urdf, estimate, model = (predictions[k].pooled for k in ("urdf", "estimate", "consistent"))
    if model > urdf:
        return Choice(nominal.copy(), "urdf", predictions, [
            f"the identified model predicts the training log worse than the URDF "
            f"({100 * model:.2f} % against {100 * urdf:.2f} %; base-parameter estimate "
            f"{100 * estimate:.2f} %): identified.urdf keeps the URDF's inertials and "
            f"friction"])
    warnings = []
    if model > (1 + CONSISTENT_MARGIN) * estimate and model - estimate > CONSISTENT_FLOOR:
        warnings.append(
            f"the physically consistent model predicts the training log "
            f"{100 * (model / estimate - 1):.0f} % worse than the base-parameter estimate "
            f"({100 * model:.2f} % against {100 * estimate:.2f} %, more than "
            f"{100 * CONSISTENT_MARGIN:.0f} %): no physically consistent model of this "
            f"URDF's kinematics fits the data as well (unmodelled effects, wrong kinematics "
            f"or units, a joint whose torque is not in the log); identified.urdf is "
            f"written all the same" + (
                f". The model class has no {', '.join(missing_terms)}: a drive's inertia or "
                "a torque offset that the links must stand in for bends their masses; "
                "--joint-terms names them (without the option the log chooses them by "
                "cross-validation)"
                if missing_terms else ""))
    if link_names:
        warnings += implausible_masses(consistent, nominal, link_names)
    return Choice(consistent, "consistent", predictions, warnings)
