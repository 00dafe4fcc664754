"""What `identify --robot` writes into its output folder: velocities.csv, parameters.csv,
identified.urdf, summary.json, the velocities' figure and the joint terms' sidecar."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..json_files import write_json
from .consistency import (
    write_identified_urdf,
)
from .held_joints import locked_record
from .joint_log import JointLog
from .joint_terms import (
    SIDECAR_NAME,
    write_sidecar,
)
from .layout import ParameterLayout
from .pipeline import Identification
from .urdf import Robot

# what write_results writes into the output folder
WRITE_ROWS = 1 << 16  # rows of velocities.csv formatted at a time
PLOT_BINS = 4000      # stretches of a long log's velocity plot (plot_samples)
OUTPUT_NAMES = ("velocities.csv", "parameters.csv", "identified.urdf", "summary.json",
                "velocities.png", SIDECAR_NAME)


def _assessment_json(result: Identification) -> dict:
    """summary.json's record of the training-log predictions, the consistent projection,
    what identified.urdf holds and the warnings."""
    out: dict = {"passive_joints": result.passive, "unmeasured_joints": result.unmeasured,
                 "warnings": result.warnings}
    if result.choice is not None:
        out["training_prediction"] = {
            **{name: p.as_json() for name, p in result.choice.predictions.items()},
            "definition": "RMS of (predicted - measured torque) over RMS of the measured "
                          "torque over the joint equations the regression used, per joint "
                          "and pooled; urdf: the input URDF, estimate: the base-parameter "
                          "least squares, consistent: the physically consistent parameters"}
        out["identified_urdf_holds"] = result.choice.written
    if result.projection is not None:
        out["consistency"] = result.projection.as_json()
    return out


def _terms_json(result: Identification, names: list[str]) -> dict:
    """summary.json's record of the extra joint terms and how they were chosen (none
    asked for: nothing)."""
    terms = result.terms
    chosen = ({} if result.terms_choice is None else
              {"joint_terms_choice": result.terms_choice.as_dict()})
    if not terms.any:
        return chosen
    n = len(names)
    values, errors = result.term_values(n), result.term_std_errors(n).reshape(n, -1)
    record: dict = {
        "terms": list(terms.kinds), "smooth_coulomb_velocity": terms.smooth_coulomb,
        "values": {name: dict(zip(terms.kinds, values[i].tolist()))
                   for i, name in enumerate(names)},
        "std_errors": {name: {kind: None if np.isnan(e) else float(e)
                              for kind, e in zip(terms.kinds, errors[i])}
                       for i, name in enumerate(names)},
        "written_to": SIDECAR_NAME if not result.urdf_kept else
        "nowhere: identified.urdf keeps the URDF's values"}
    if terms.asymmetric_coulomb:
        record["coulomb_in_urdf"] = "the mean of coulomb_positive and coulomb_negative"
    return {"joint_terms": record, **chosen}


def write_results(out: Path, robot: Robot, log: JointLog, result: Identification,
                  data_name: str) -> list[Path]:
    """velocities.csv, parameters.csv, identified.urdf, summary.json, a plot and
    joint_terms.csv (the extra joint terms; only its header without them or when
    identified.urdf keeps the URDF's values, so that validate never reads an earlier
    run's terms beside this run's URDF)."""
    out.mkdir(parents=True, exist_ok=True)
    names = robot.joint_names
    velocities = out / "velocities.csv"
    with velocities.open("w") as handle:  # in chunks: no copy of the log's length
        header = ",".join(["t"] + [f"qd{i + 1}" for i in range(robot.n)])
        for start in range(0, max(len(log.t), 1), WRITE_ROWS):
            rows = slice(start, start + WRITE_ROWS)
            np.savetxt(handle, np.column_stack([log.t[rows], result.velocity[rows]]),
                       delimiter=",", header=header if start == 0 else "", comments="")
    parameters = out / "parameters.csv"
    n = robot.n
    extra = result.terms.count(n)
    nominal_beta = result.base.project(np.concatenate([robot.parameters(), np.zeros(extra)]))
    projection = result.projection
    consistent_beta = result.base.project(result.pi if projection is None else projection.pi)
    # without a projection the consistent values are the estimate's, as are their errors
    consistent_std = result.fit.std_error if projection is None else projection.base_std
    with parameters.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["parameter", "urdf", "estimate", "std_error", "consistent",
                         "consistent_std_error", "definition"])
        for k in range(result.base.count):
            writer.writerow([result.base.names[k], f"{nominal_beta[k]:.10g}",
                             f"{result.fit.theta[k]:.10g}", f"{result.fit.std_error[k]:.3g}",
                             f"{consistent_beta[k]:.10g}", f"{consistent_std[k]:.3g}",
                             result.base.description(k)])
    urdf = out / "identified.urdf"
    kept = result.urdf_kept
    standard = result.standard(n)
    layout = ParameterLayout(n, len(result.terms.kinds))
    write_identified_urdf(robot, standard, urdf,
                          f"the input URDF's inertials and joint dynamics, kept: the model "
                          f"identified from {data_name} predicts it worse (summary.json)"
                          if kept else
                          f"inertials and joint dynamics identified from {data_name} by "
                          f"python -m harness identify")
    sidecar = out / SIDECAR_NAME
    write_sidecar(sidecar, result.terms, names, [joint.kind for joint in robot.joints],
                  None if kept or not result.terms.any else result.pi[layout.extra],
                  result.term_std_errors(n))
    summary = out / "summary.json"
    write_json(summary, {
        "joints": names,
        "viscous": dict(zip(names, standard[layout.viscous_levels].tolist())),
        "coulomb": dict(zip(names, standard[layout.coulomb_levels].tolist())),
        "masses": dict(zip([j.child_link for j in robot.joints],
                           result.pi[layout.masses].tolist())),
        "residual_rms": dict(zip(names, result.fit.equation_rms.tolist())),
        "condition_number": result.fit.condition,
        "base_parameters": result.base.count,
        "samples_used": int(len(result.used)),
        "regression_window_s": result.window,
        "resampled": log.resampled,
        "locked_joints": robot.locked_at,
        "mass_bounds": (None if result.mass_bounds is None or not result.mass_bounds.any
                        else result.mass_bounds.as_json(robot)),
        "held_joints": locked_record(robot, log),
        **_assessment_json(result),
        **_terms_json(result, names),
        **({} if result.velocity_window is None else
           {"velocity_window_s": dict(zip(names, result.velocity_window.tolist()))}),
    })
    plot = out / "velocities.png"
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(n, 1, sharex=True, figsize=(8, 1.6 * n + 1), squeeze=False)
    for i in range(n):
        shown = plot_samples(result.velocity[:, i])
        axes[i, 0].plot(log.t[shown], result.velocity[shown, i], lw=0.8)
        axes[i, 0].set_ylabel(f"qd{i + 1}")
    axes[-1, 0].set_xlabel("t [s]")
    figure.tight_layout()
    figure.savefig(plot, dpi=90)
    plt.close(figure)
    return [velocities, parameters, urdf, summary, plot, sidecar]


def plot_samples(x: np.ndarray, bins: int = PLOT_BINS) -> np.ndarray | slice:
    """The samples of x (N,) that a line plot needs: all of a short signal; of a long
    one, the first and last and each of `bins` stretches' smallest and largest value
    in time order (the
    envelope the dense line fills at the plot's resolution, for a small part of the
    memory matplotlib takes for every point)."""
    if len(x) <= 2 * bins:
        return slice(None)
    width = -(-len(x) // bins)  # samples a stretch
    whole = len(x) // width * width
    stretches = x[:whole].reshape(-1, width)
    starts = np.arange(0, whole, width)[:, None]
    extremes = [starts + np.column_stack([stretches.argmin(axis=1), stretches.argmax(axis=1)])]
    if whole < len(x):
        rest = x[whole:]
        extremes.append(whole + np.array([[rest.argmin(), rest.argmax()]]))
    ends = np.array([[0, len(x) - 1]])  # the plot's time axis as the log's
    return np.unique(np.concatenate([ends, *extremes]))
