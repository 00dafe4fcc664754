"""Joint terms beyond the URDF's model: offset, armature, asymmetric and smooth Coulomb friction.

The C core's model has, per joint i, viscous friction fv_i q_i' and symmetric Coulomb
friction fc_i sign(q_i').  A real arm's drive often needs more, each switchable:

- offset: a constant torque o_i (any sign: a sensor's or a drive's bias, an unmodelled
  spring at its mean), tau_i += o_i;
- armature: the reflected rotor inertia Ia_i >= 0 of a geared drive, tau_i += Ia_i q_i'';
- asymmetric Coulomb: fc_i sign(q_i') replaced by fc+_i [q_i' > 0] - fc-_i [q_i' < 0]
  (both >= 0);
- smooth Coulomb: fc_i sign(q_i') replaced by fc_i tanh(q_i' / v_s), v_s a velocity
  scale the user gives (rad/s or m/s).

They enter the identification as extra regressor columns after the core's 12 n (in the
order of `names`: per joint, its terms in TERM_ORDER), built here from q' and q'' at the
regression's samples; the core's Coulomb column is replaced in place (tanh) or left out
(asymmetric: the two levels replace it).  Where a joint moves, [q' > 0] + [q' < 0] = 1:
with an offset, the two Coulomb levels and the offset are collinear and only two of their
combinations are identified (base_parameters keeps the Coulomb levels and folds the
offset into them).  Asymmetric and smooth Coulomb together are refused: tanh's two
halves and an offset are nearly collinear, and a smooth level per direction is a model
no drive maker states.

The identified terms that a URDF cannot hold go to the sidecar joint_terms.csv (columns
joint, term, value, std_error, unit), which validate reads back (`read_sidecar`,
`torque_change`).
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..inputs import InputError, read_text
from .filtered_regression import first_order, lfilter_zi_at
from .layout import ParameterLayout
from .urdf import LARGEST

# the terms' names in joint_terms.csv and parameters.csv, in the regressor's order per joint
OFFSET, ARMATURE, COULOMB_POSITIVE, COULOMB_NEGATIVE = (
    "offset", "armature", "coulomb_positive", "coulomb_negative")
TERM_ORDER = (OFFSET, ARMATURE, COULOMB_POSITIVE, COULOMB_NEGATIVE)
# the smooth Coulomb friction's velocity scale: a setting, not identified, in the sidecar
SMOOTH_VELOCITY = "smooth_coulomb_velocity"
# the --joint-terms items and the switches they set
OPTION_ITEMS = {"offset": "offset", "armature": "armature",
                "asymmetric-coulomb": "asymmetric_coulomb"}
SIDECAR_NAME = "joint_terms.csv"
SIDECAR_COLUMNS = ("joint", "term", "value", "std_error", "unit")
SIDECAR_MAX_BYTES = 1 << 20  # a sidecar is read whole: larger files are refused


class JointTermsError(ValueError):
    """Joint terms asked for or read that cannot be used; the message names them."""


@dataclass(frozen=True)
class JointTerms:
    """Which extra joint terms the model has (each for every joint)."""

    offset: bool = False
    armature: bool = False
    asymmetric_coulomb: bool = False
    smooth_coulomb: float | None = None  # v_s [rad/s or m/s]; None: sign(q')

    def __post_init__(self) -> None:
        if self.smooth_coulomb is not None and not (
                math.isfinite(self.smooth_coulomb) and self.smooth_coulomb > 0):
            raise JointTermsError(f"the smooth Coulomb velocity scale must be a finite number "
                                  f"> 0, not {self.smooth_coulomb!r}")
        if self.smooth_coulomb is not None and self.asymmetric_coulomb:
            raise JointTermsError("asymmetric and smooth Coulomb friction cannot be combined "
                                  "(a smooth level per direction and an offset are nearly "
                                  "collinear): choose one")

    @property
    def any(self) -> bool:
        """True if the model differs from the core's."""
        return bool(self.kinds) or self.smooth_coulomb is not None

    @property
    def kinds(self) -> tuple[str, ...]:
        """The extra terms of each joint, in the regressor's order."""
        on = {OFFSET: self.offset, ARMATURE: self.armature,
              COULOMB_POSITIVE: self.asymmetric_coulomb,
              COULOMB_NEGATIVE: self.asymmetric_coulomb}
        return tuple(kind for kind in TERM_ORDER if on[kind])

    def count(self, n: int) -> int:
        """The number of extra columns of an n-joint robot."""
        return len(self.kinds) * n

    def names(self, joint_names: list[str]) -> list[str]:
        """The extra parameters' names, "joint.term", in the columns' order."""
        return [f"{joint}.{kind}" for joint in joint_names for kind in self.kinds]

    def nonnegative(self, n: int) -> np.ndarray:
        """(count(n),) True for the terms that are >= 0 (all but the offsets)."""
        return np.array([kind != OFFSET for _ in range(n) for kind in self.kinds], dtype=bool)

    def replaced(self, n: int) -> np.ndarray:
        """The core's columns (of 12 n) this model leaves out: each joint's Coulomb
        column when the asymmetric levels replace it."""
        return (ParameterLayout(n).coulomb_indices if self.asymmetric_coulomb
                else np.zeros(0, dtype=int))

    def signals(self, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """(N, n, k) each joint's extra terms' column values at velocities and
        accelerations (N, n): offset 1, armature q'', the Coulomb levels [q' > 0] and
        -[q' < 0]."""
        values = {OFFSET: np.ones_like(qd), ARMATURE: qdd,
                  COULOMB_POSITIVE: (qd > 0).astype(float),
                  COULOMB_NEGATIVE: -(qd < 0).astype(float)}
        kinds = self.kinds
        if not kinds:
            return np.zeros((*qd.shape, 0))
        return np.stack([values[kind] for kind in kinds], axis=-1)

    def coulomb(self, qd: np.ndarray) -> np.ndarray:
        """The symmetric Coulomb column this model has in place of the core's sign(q')
        (N, n): tanh(q' / v_s), sign(q'), or 0 where the asymmetric levels replace it."""
        if self.asymmetric_coulomb:
            return np.zeros_like(qd)
        if self.smooth_coulomb is not None:
            return np.tanh(qd / self.smooth_coulomb)
        return np.sign(qd)

    def columns(self, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """The extra regressor columns (N, n, k n) at (N, n) velocities and accelerations:
        joint i's terms act on its own equation only."""
        return _block_diagonal(self.signals(qd, qdd))

    def extend(self, Y: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """The core's regressor Y (N, n, 12 n) with this model's Coulomb columns and the
        extra columns appended: (N, n, 12 n + k n)."""
        n = qd.shape[1]
        out = np.concatenate([Y, self.columns(qd, qdd)], axis=2)
        if self.asymmetric_coulomb or self.smooth_coulomb is not None:
            out[:, np.arange(n), ParameterLayout(n).coulomb_indices] = self.coulomb(qd)
        return out

    def extend_filtered(self, Y: np.ndarray, velocity: np.ndarray, h: float, tau: float,
                        used: np.ndarray) -> np.ndarray:
        """The filtered regressor of filtered_regression (at the samples `used`) with this
        model's columns: each term's signal through the same causal filter, in the same
        momentum form (the armature's Ia q'' as the derivative of its momentum Ia q')."""
        n = velocity.shape[1]
        out = np.concatenate([Y, np.zeros((len(Y), n, self.count(n)))], axis=2)
        layout = ParameterLayout(n, len(self.kinds))
        zeros = np.zeros_like(velocity[:, 0])
        for i in range(n):
            v = velocity[:, i:i + 1]
            rest = self.signals(v, np.zeros_like(v))[:, 0, :]  # armature: no rest part
            for j, kind in enumerate(self.kinds):
                momentum = v[:, 0] if kind == ARMATURE else zeros
                out[:, i, layout.term(i, j)] = _filtered(momentum, rest[:, j], h, tau, used)
            if self.asymmetric_coulomb or self.smooth_coulomb is not None:
                out[:, i, layout.coulomb(i)] = _filtered(zeros, self.coulomb(v)[:, 0], h,
                                                         tau, used)
        return out

    def units(self, kinds_of_joints: list[str]) -> list[str]:
        """Each extra parameter's unit (a joint's kind: "revolute" or "prismatic")."""
        table = {OFFSET: ("N.m", "N"), ARMATURE: ("kg.m^2", "kg"),
                 COULOMB_POSITIVE: ("N.m", "N"), COULOMB_NEGATIVE: ("N.m", "N")}
        return [table[kind][joint == "prismatic"] for joint in kinds_of_joints
                for kind in self.kinds]


def check_directions(terms: JointTerms, speed: np.ndarray, mask: np.ndarray,
                     names: list[str]) -> str | None:
    """None, or why the terms cannot be identified from equations where each joint moves
    one way only: speed (N, n) at the regression's samples, mask (N, n) the equations it
    uses.  A joint that never moves backwards (or forwards) has no equation for one
    Coulomb level, and its offset and Coulomb friction are then collinear."""
    if not (terms.offset or terms.asymmetric_coulomb):
        return None
    problems = []
    for i, name in enumerate(names):
        if not mask[:, i].any():
            continue  # no equation at all (an unmeasured torque): its terms are not fitted
        used = speed[mask[:, i], i]
        for word, moving in (("forwards (q' > 0)", used > 0), ("backwards (q' < 0)", used < 0)):
            if not moving.any():
                problems.append(f"joint {name!r} never moves {word} in the equations used")
    if not problems:
        return None
    return ("; ".join(problems) + ": its offset and Coulomb friction (or its Coulomb "
            "level that way) cannot be identified; leave out --joint-terms offset and "
            "asymmetric-coulomb, or log a trajectory that moves each joint both ways")


def _block_diagonal(signals: np.ndarray) -> np.ndarray:
    """(N, n, k) per-joint values as (N, n, k n) columns, joint i's in its own row."""
    N, n, k = signals.shape
    out = np.zeros((N, n, k * n))
    for i in range(n):
        out[:, i, k * i:k * i + k] = signals[:, i, :]
    return out


def _filtered(momentum: np.ndarray, rest: np.ndarray, h: float, tau: float,
              used: np.ndarray) -> np.ndarray:
    """One column of filtered_regression's form at the samples `used`: the difference
    quotient of the filtered momentum plus the mean of the filtered rest over the step
    before each sample (the filter at rest at the first sample)."""
    from scipy.signal import lfilter

    b, a = first_order(tau, h)
    filtered = []
    for signal in (momentum, rest):
        x = signal[:, None]
        for _ in range(2):
            x, _state = lfilter(b, a, x, axis=0, zi=lfilter_zi_at(b, a, x[0]))
        filtered.append(x[:, 0])
    m, r = filtered
    before = np.maximum(used - 1, 0)
    return (m[used] - m[before]) / h + 0.5 * (r[used] + r[before])


def parse_terms(items: str | None, smooth: float | None) -> JointTerms:
    """JointTerms of --joint-terms ITEM,... (offset, armature, asymmetric-coulomb; none:
    no extra term) and --smooth-coulomb VS; JointTermsError names a bad item or
    combination."""
    if items is not None and items.strip() == "none":
        return JointTerms(smooth_coulomb=smooth)
    switches: dict[str, bool] = {}
    for item in (part.strip() for part in (items or "").split(",")):
        if not item:
            continue
        if item not in OPTION_ITEMS:
            raise JointTermsError(f"--joint-terms item {item!r} is not one of "
                                  f"{', '.join(OPTION_ITEMS)} (or none, or auto alone)")
        switches[OPTION_ITEMS[item]] = True
    if items is not None and not switches:
        raise JointTermsError(f"--joint-terms {items!r} names no term (one or more of "
                              f"{', '.join(OPTION_ITEMS)}, comma-separated)")
    return JointTerms(**switches, smooth_coulomb=smooth)


@dataclass
class Sidecar:
    """The joint terms of a joint_terms.csv: the model and each joint's values."""

    terms: JointTerms
    values: np.ndarray  # (n, k): joint i's values of terms.kinds
    path: Path

    def torque_change(self, qd: np.ndarray, qdd: np.ndarray, coulomb: np.ndarray
                      ) -> np.ndarray:
        """What the terms add to the URDF's torques (N, n) at velocities and accelerations
        (N, n): the extra terms, and the URDF's Coulomb friction (levels `coulomb` (n,),
        as sign(q')) replaced by this model's."""
        extra = np.einsum("kij,ij->ki", self.terms.signals(qd, qdd), self.values)
        return extra + (self.terms.coulomb(qd) - np.sign(qd)) * coulomb[None, :]

    def coulomb_torque(self, qd: np.ndarray, coulomb: np.ndarray) -> np.ndarray:
        """The Coulomb friction this model predicts at velocities (N, n): the symmetric
        level (`coulomb` (n,), the URDF's) on terms.coulomb(q'), plus the levels per
        direction."""
        torque = self.terms.coulomb(qd) * coulomb[None, :]
        levels = [j for j, kind in enumerate(self.terms.kinds)
                  if kind in (COULOMB_POSITIVE, COULOMB_NEGATIVE)]
        if levels:
            signals = self.terms.signals(qd, np.zeros_like(qd))[:, :, levels]
            torque = torque + np.einsum("kij,ij->ki", signals, self.values[:, levels])
        return torque


def write_sidecar(path: Path, terms: JointTerms, joint_names: list[str],
                  joint_kinds: list[str], values: np.ndarray | None,
                  std_errors: np.ndarray | None) -> None:
    """joint_terms.csv: each joint's extra terms (values (k n,), std_errors (k n,), NaN:
    not identified alone) and the smooth Coulomb velocity scale; only the header when
    values is None (no terms, or the URDF's model kept)."""
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(SIDECAR_COLUMNS)
        if values is None:
            return
        k = len(terms.kinds)
        units = terms.units(joint_kinds)
        errors = np.full(len(values), np.nan) if std_errors is None else std_errors
        for i, joint in enumerate(joint_names):
            for j, kind in enumerate(terms.kinds):
                index = k * i + j
                writer.writerow([joint, kind, f"{values[index]:.10g}",
                                 "" if np.isnan(errors[index]) else f"{errors[index]:.3g}",
                                 units[index]])
            if terms.smooth_coulomb is not None:
                writer.writerow([joint, SMOOTH_VELOCITY, f"{terms.smooth_coulomb:.10g}", "",
                                 "m/s" if joint_kinds[i] == "prismatic" else "rad/s"])


def read_sidecar(path: Path, joint_names: list[str]) -> Sidecar:
    """The joint terms of joint_terms.csv for a robot with these joints; JointTermsError
    names a bad row (an unknown joint or term, a value that is not a number, a term
    given to some joints only)."""
    try:  # read with a cap, never trusting st_size: a device (/dev/zero) says 0
        text = read_text(path, SIDECAR_NAME, limit=SIDECAR_MAX_BYTES)
    except InputError as error:
        if "larger than" in str(error):
            raise JointTermsError(f"{path}: more than {SIDECAR_MAX_BYTES} bytes; a "
                                  f"{SIDECAR_NAME} is a few hundred ({error})") from None
        if "UTF-8" in str(error):
            raise JointTermsError(f"{path}: not a CSV file in UTF-8 ({error})") from None
        raise JointTermsError(str(error)) from None
    try:
        rows = list(csv.DictReader(io.StringIO(text, newline="")))
        header = rows[0].keys() if rows else None
    except csv.Error as error:
        raise JointTermsError(f"{path}: not a CSV file in UTF-8 ({error})") from None
    if header is not None and not set(SIDECAR_COLUMNS) <= set(header):
        raise JointTermsError(f"{path}: the columns must be {', '.join(SIDECAR_COLUMNS)}")
    found: dict[tuple[str, str], float] = {}
    seen: dict[tuple[str, str], int] = {}  # the line of each joint's term
    smooth: set[float] = set()
    for line, row in enumerate(rows, start=2):
        joint, kind = row["joint"], row["term"]
        if joint not in joint_names:
            raise JointTermsError(f"{path} line {line}: joint {joint!r} is not one of the "
                                  f"robot's ({', '.join(joint_names)})")
        if kind not in (*TERM_ORDER, SMOOTH_VELOCITY):
            raise JointTermsError(f"{path} line {line}: term {kind!r} is not one of "
                                  f"{', '.join((*TERM_ORDER, SMOOTH_VELOCITY))}")
        try:
            value = float(row["value"])
        except (TypeError, ValueError):
            value = math.nan
        if not math.isfinite(value):
            raise JointTermsError(f"{path} line {line}: value {row['value']!r} is not a "
                                  f"finite number")
        if abs(value) > LARGEST:  # as for a URDF: products of such values overflow
            raise JointTermsError(f"{path} line {line}: value {row['value']!r} of {kind} is "
                                  f"beyond {LARGEST:g} (SI units): not a joint's")
        if (joint, kind) in seen:
            raise JointTermsError(f"{path} line {line}: joint {joint!r} has a second {kind} "
                                  f"(line {seen[(joint, kind)]}); give each once")
        seen[(joint, kind)] = line
        if kind == SMOOTH_VELOCITY:
            smooth.add(value)
        else:
            found[(joint, kind)] = value
    kinds = {kind for _, kind in found}
    if len(smooth) > 1:
        raise JointTermsError(f"{path}: different smooth Coulomb velocity scales "
                              f"({', '.join(map(str, sorted(smooth)))}); one for all joints")
    try:
        terms = JointTerms(offset=OFFSET in kinds, armature=ARMATURE in kinds,
                           asymmetric_coulomb=bool(kinds & {COULOMB_POSITIVE,
                                                            COULOMB_NEGATIVE}),
                           smooth_coulomb=smooth.pop() if smooth else None)
    except JointTermsError as error:
        raise JointTermsError(f"{path}: {error}") from None
    values = np.empty((len(joint_names), len(terms.kinds)))
    for i, joint in enumerate(joint_names):
        for j, kind in enumerate(terms.kinds):
            if (joint, kind) not in found:
                raise JointTermsError(f"{path}: joint {joint!r} has no {kind} (the file gives "
                                      f"it to other joints: every joint needs it)")
            values[i, j] = found[(joint, kind)]
    return Sidecar(terms, values, Path(path))
