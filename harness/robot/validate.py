"""`python -m harness validate LOG --robot ROBOT.urdf --out DIR`: how well a URDF (the
maker's, or an identify run's identified.urdf) predicts the torques of a log.

The positions pass the same zero-phase Savitzky-Golay filter as the identification
(`savitzky_golay`: q, q', q'' and the measured torques alike; by default over the window
identify would choose for this log), the model's Coulomb friction (a step at every
reversal, which the filtered measured torque has smoothed) passes it too, the URDF's inverse
dynamics with its friction predicts the torques, and the score is the field's: the
RMS of the prediction error over the RMS of the measured torque, per joint and pooled
over the joints, the filter's edges left out.  A joint whose measured torque is 0
throughout (a passive joint) has no relative error of its own (null in validation.json);
its predicted torque still counts in the pooled error.

The joint terms an identify run wrote beside its identified.urdf (joint_terms.csv:
offsets, armature, asymmetric or smooth Coulomb friction, harness.robot.joint_terms)
join the prediction when that file sits next to the URDF or --joint-terms-file names
it; without it, the URDF's model alone."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..json_files import write_json
from .joint_log import JointLog, LogError
from .joint_terms import (
    COULOMB_NEGATIVE,
    COULOMB_POSITIVE,
    SIDECAR_NAME,
    JointTerms,
    JointTermsError,
    Sidecar,
    read_sidecar,
)
from .layout import ParameterLayout, core_layout
from .smoothing import regression_window, savitzky_golay, smooth_column, velocity_windows
from .urdf import Robot

OUTPUT_NAMES = ("validation.json", "validation.png")


def scoring_window(log: JointLog) -> float:
    """The window validate takes when none is given: identify's (regression_window) for
    this log, so that a coarse encoder's steps are not scored as torque errors."""
    try:
        return regression_window(velocity_windows(log.q, log.step))
    except ValueError as error:  # too short a log
        raise LogError(str(error)) from None


def coulomb_torque(robot: Robot, qd: np.ndarray, sidecar: Sidecar | None = None
                   ) -> np.ndarray:
    """The Coulomb friction (N, n) that a URDF's model (with a sidecar's terms) predicts at
    the velocities qd: a step at every reversal."""
    coulomb = robot.arrays()["friction"][:, core_layout().coulomb]
    return (coulomb[None, :] * np.sign(qd) if sidecar is None
            else sidecar.coulomb_torque(qd, coulomb))


def filtered_friction_columns(log: JointLog, qd: np.ndarray, window: float,
                              terms: JointTerms | None = None) -> dict[int, tuple[int, np.ndarray]]:
    """The regressor's Coulomb columns (the core's sign(q'), or the terms' tanh or levels
    per direction) through the filter, over the whole log: {column: (joint, values (N,))}
    for the column's entry in that joint's equation.  A regression-based score puts them in
    place of the unfiltered steps, as torque_errors does for a URDF's model."""
    n = qd.shape[1]
    terms = terms or JointTerms()
    out: dict[int, tuple[int, np.ndarray]] = {}
    coulomb = filtered(log, terms.coulomb(qd), window)
    layout = ParameterLayout(n, len(terms.kinds))
    for i in range(n):
        out[layout.coulomb(i)] = (i, coulomb[:, i])
    signals = terms.signals(qd, np.zeros_like(qd))
    for j, kind in enumerate(terms.kinds):
        if kind in (COULOMB_POSITIVE, COULOMB_NEGATIVE):
            level = filtered(log, signals[:, :, j], window)
            for i in range(n):
                out[layout.term(i, j)] = (i, level[:, i])
    return out


def filtered(log: JointLog, x: np.ndarray, window: float) -> np.ndarray:
    """Each column of x (N, n) through the Savitzky-Golay filter of `window` s."""
    return np.column_stack([smooth_column(log, x[:, i], window) for i in range(x.shape[1])])


def torque_errors(robot: Robot, log: JointLog, window: float, sidecar: Sidecar | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, float | None], float]:
    """(t, measured, predicted torques, relative error per joint (None: a joint whose
    torque is 0, passive, or not in the log: unmeasured), pooled over the measured joints)
    on the samples a window away from the log's ends; the sidecar's joint terms
    (read_sidecar) added to the URDF's prediction."""
    q, qd, qdd, u = savitzky_golay(log, window)
    edge = int(np.ceil(window / log.step - 1e-9))  # not one more for a step's rounding
    inside = slice(edge, len(log.t) - edge)
    if inside.stop - inside.start < 10:
        raise LogError(f"the log ({log.t[-1] - log.t[0]:g} s) is too short for a "
                       f"{window:g} s window")
    predicted = robot.rigid_body().inverse_dynamics(q[inside], qd[inside], qdd[inside])
    if sidecar is not None:
        predicted += sidecar.torque_change(qd[inside], qdd[inside],
                                           robot.arrays()["friction"][:, core_layout().coulomb])
    # the model's Coulomb steps through the filter the measured torque passed
    steps = coulomb_torque(robot, qd, sidecar)
    predicted += (filtered(log, steps, window) - steps)[inside]
    measured = u[inside]
    error = predicted - measured
    per_joint: dict[str, float | None] = {}
    for i, name in enumerate(robot.joint_names):
        scale = float(np.sqrt(np.mean(measured[:, i] ** 2)))
        per_joint[name] = (float(np.sqrt(np.mean(error[:, i] ** 2))) / scale
                           if scale > 0 and i not in log.unmeasured else None)
    kept = log.measured
    pooled = float(np.linalg.norm(error[:, kept]) / np.linalg.norm(measured[:, kept]))
    return log.t[inside], measured, predicted, per_joint, pooled


def write_validation(out: Path, urdf: str, data: str, window: float, t: np.ndarray,
                     measured: np.ndarray, predicted: np.ndarray,
                     per_joint: dict[str, float | None],
                     pooled: float, joint_terms: str | None = None,
                     unmeasured: tuple[str, ...] = (),
                     held_joints: dict[str, dict] | None = None) -> None:
    """validation.json and validation.png (measured and predicted torques per joint);
    joint_terms: the joint_terms.csv whose terms the prediction includes (None: none);
    held_joints: each held joint's position and its source, as summary.json's
    (harness.robot.held_joints.locked_record)."""
    write_json(out / "validation.json", {
        "urdf": urdf, "joint_terms": joint_terms, "log": data,
        "relative_error": {"per_joint": per_joint, "pooled": pooled},
        "unmeasured_joints": list(unmeasured),
        "held_joints": held_joints or {},
        "definition": "RMS of (predicted - measured torque) over RMS of the measured torque, "
                      "per joint and pooled over the joints; zero-phase Savitzky-Golay "
                      "derivatives of q and the same filter on the measured torque and on "
                      "the model's Coulomb friction (steps at the reversals), the window's "
                      "edges left out; null for a joint whose torque is 0 (passive) or "
                      "not measured (unmeasured_joints)",
        "window": window, "samples": int(len(t)),
    })
    from matplotlib.figure import Figure

    n = measured.shape[1]
    fig = Figure(figsize=(9, 1.8 * n + 0.8), layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for i, (ax, name) in enumerate(zip(axes, per_joint)):
        ax.plot(t, measured[:, i], lw=0.8, color="k", label="measured")
        ax.plot(t, predicted[:, i], lw=0.8, color="C1", label="predicted")
        ax.set_ylabel(f"{name}\n{_percent(per_joint[name], 1, name in unmeasured)}",
                      fontsize=8)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{Path(urdf).name} on {Path(data).name}: pooled {100 * pooled:.2f} %",
                 fontsize=10)
    fig.savefig(out / "validation.png", dpi=100)


def _percent(relative: float | None, digits: int, unmeasured: bool = False) -> str:
    """A relative error in %, or what None means (a joint whose torque is 0, or not in
    the log)."""
    if relative is None:
        return "n/a (not measured)" if unmeasured else "n/a (torque 0: passive)"
    return f"{100 * relative:.{digits}f} %"


def sidecar_path(urdf: str, given: str | None) -> Path | None:
    """The joint_terms.csv to read: the one given, else the one next to the URDF if
    there is one, else None."""
    if given is not None:
        return Path(given)
    beside = Path(urdf).parent / SIDECAR_NAME
    if beside.is_file():
        return beside
    if os.path.lexists(beside):  # a folder, pipe, device or broken link: never skipped unsaid
        raise JointTermsError(f"{beside}: beside the URDF but not a regular file; move it away "
                              "or name the joint terms with --joint-terms-file")
    return None


def validate_command(args) -> int:
    """`validate LOG --robot URDF --out DIR`: exit 0, or 2 for bad input."""
    import sys

    from ..outputs import Outputs, shown
    from .cli import column_mapping, robot_and_log
    from .held_joints import locked_record, logged_lines
    from .log_units import UnitError
    from .urdf import UrdfError

    mapping = column_mapping(args.columns, "validate")
    if mapping is None:
        return 2
    try:
        terms_file = sidecar_path(args.robot, getattr(args, "joint_terms_file", None))
    except JointTermsError as error:
        print(f"harness validate: {error}", file=sys.stderr)
        return 2
    inputs = [args.data, args.robot] + ([terms_file] if terms_file is not None else [])
    try:
        with Outputs(args.out, "validate", inputs=inputs, names=OUTPUT_NAMES) as outputs:
            robot, log = robot_and_log(args, mapping)
            window = scoring_window(log) if args.window is None else args.window
            sidecar = (None if terms_file is None else
                       read_sidecar(terms_file, robot.joint_names))
            if sidecar is not None and not sidecar.terms.any:
                sidecar = None  # only a header: the URDF's model alone
            t, measured, predicted, per_joint, pooled = torque_errors(robot, log, window,
                                                                      sidecar)
            unmeasured = tuple(robot.joint_names[i] for i in log.unmeasured)
            write_validation(outputs.staging, args.robot, args.data, window, t,
                             measured, predicted, per_joint, pooled,
                             None if sidecar is None else str(terms_file), unmeasured,
                             locked_record(robot, log))
    except (UrdfError, LogError, UnitError, JointTermsError) as error:
        print(f"harness validate: {error}", file=sys.stderr)
        return 2
    print(f"wrote {shown(*outputs.written)}")
    if sidecar is not None:
        settings = sidecar.terms
        described = ", ".join(
            [*settings.kinds] + ([f"smooth Coulomb (v_s {settings.smooth_coulomb:g})"]
                                 if settings.smooth_coulomb is not None else []))
        print(f"  the prediction includes the joint terms of {terms_file}: {described}")
    elif terms_file is not None:
        print(f"  {terms_file} holds no joint terms: the URDF's model alone")
    if log.resampled:
        print(f"  {args.data}: {log.resampled}")
    for line in logged_lines(robot, log):
        print(f"  {line}")
    for name, relative in per_joint.items():
        print(f"  {name}: relative torque error {_percent(relative, 3, name in unmeasured)}")
    print(f"  pooled: {100 * pooled:.3f} % (Savitzky-Golay window {window:.3g} s)")
    return 0
