"""The RobotObserver FMU's parameters from a URDF, and runs of the FMU over a joint log.

    python -m harness robot-fmu-parameters ROBOT.urdf --out robot.ssv [--unknown payload]

writes the robot's kinematic and inertial data, the base columns of its regressor and
the nominal base parameters as an SSP parameter set (SSV, FMI 2 variable names such as
``link[2,1]``), which SSP tools load as they are; ``start_values`` turns the same
parameters into fmpy start values (FMI 2 structured names; an FMI 3 importer sets the
arrays of ``fmu_parameters`` whole, padded to 7 rows), so that an FMI tool chain sets them
once.  ``run_fmu`` replays a log through the FMU with fmpy.
"""
from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from ..names import plain
from .base_parameters import base_parameters
from .joint_log import JointLog
from .layout import ParameterLayout
from .native import core_defaults
from .urdf import Robot, UrdfError

INTEGERS = {"n", "identifier", "base_count", "joint_type", "base_columns", "max_internal_steps"}
IDENTIFIERS = {"off": 0, "lsm": 1, "mff": 2}
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
#: Joints the RobotObserver FMU holds at most (the rows of its arrays: RB_MAX_JOINTS of
#: the FMUs); the offline path takes longer chains (core_defaults().max_joints)
FMU_MAX_JOINTS = 7


def fmu_parameters(robot: Robot, unknown: str = "all", h: float = 1e-3, f_plus=10.0,
                   identifier: str = "lsm", tau: float = 0.01, rho: float = 1e-6,
                   R: float = 0.1, t_id: float = 0.2, torque_scale=None,
                   coulomb_velocity: float = 0.0, pi: np.ndarray | None = None,
                   alpha1=0.0, alpha2=0.0, min_speed: float | None = None,
                   reversal_margin: float | None = None) -> dict[str, Any]:
    """The RobotObserver parameters for `robot`: name -> scalar or array (the joints'
    rows only; the FMU's other rows keep their start values).

    unknown: "all" (every base parameter and the friction) or "payload" (the last link
    and the friction); f_plus (per joint or one value) bounds the model's acceleration
    error [rad/s^2]; alpha1, alpha2 (per joint or one value; 0: from f_plus by Theorem
    3.1) are the observer's gains; torque_scale (per joint) weighs the joints' equations; pi (12 n:
    link parameters, then friction) replaces the URDF's inertials and friction (e.g. an
    identified model); the identifier leaves out joint i's equation where |q_i'| <
    min_speed [rad/s or m/s] or q_i' reverses, and for reversal_margin [s] after (both 0:
    every equation is used; None: the core's defaults)."""
    if identifier not in IDENTIFIERS:
        raise ValueError(f"identifier {identifier!r}: one of {', '.join(IDENTIFIERS)}")
    if robot.n > FMU_MAX_JOINTS:
        raise UrdfError(f"{robot.source}: {robot.n} moving joints; the RobotObserver FMU holds "
                        f"at most {FMU_MAX_JOINTS} (identify and validate --robot take up to "
                        f"{core_defaults().max_joints}): name a shorter chain with --joints, or "
                        "lock joints with --lock")
    defaults = core_defaults()
    min_speed = defaults.min_speed if min_speed is None else min_speed
    reversal_margin = defaults.reversal_margin if reversal_margin is None else reversal_margin
    for name, value in (("min_speed", min_speed), ("reversal_margin", reversal_margin)):
        if not (np.isfinite(value) and value >= 0.0):
            raise ValueError(f"{name} must be a finite number >= 0, not {value!r}")
    arrays = robot.arrays()
    n = robot.n
    layout = ParameterLayout(n)
    if pi is not None:
        arrays["link"], arrays["friction"], _ = layout.split(pi)
    nominal = layout.join(arrays["link"], arrays["friction"])
    base = base_parameters(robot.rigid_body(), arrays["types"], robot.joint_names, unknown)
    scale = np.ones(n) if torque_scale is None else np.asarray(torque_scale, float)
    return {
        "h": h, "n": n, "identifier": IDENTIFIERS[identifier], "base_count": base.count,
        "tau": tau, "rho": rho, "R": R, "t_id": t_id, "coulomb_velocity": coulomb_velocity,
        "min_speed": float(min_speed), "reversal_margin": float(reversal_margin),
        "gravity": np.asarray(arrays["gravity"], float),
        "joint_type": np.asarray(arrays["types"], int),
        "axis": arrays["axis"].reshape(n, 3), "xyz": arrays["xyz"].reshape(n, 3),
        "rpy": arrays["rpy"].reshape(n, 3), "link": arrays["link"].reshape(n, layout.link_size),
        "friction": arrays["friction"].reshape(n, layout.friction_size),
        **{name: np.broadcast_to(np.asarray(value, float), (n,)).copy()
           for name, value in (("f_plus", f_plus), ("alpha1", alpha1), ("alpha2", alpha2))},
        "torque_scale": np.broadcast_to(scale, (n,)).copy(),
        "base_columns": np.asarray(base.base, int),
        "base_nominal": base.project(nominal),
    }


def _elements(name: str, value) -> list[tuple[str, float | int]]:
    """(FMI 2 name, value) of every element: name, name[i] or name[i,j] (1-based)."""
    array = np.asarray(value)
    cast = int if name in INTEGERS else float
    if array.ndim == 0:
        return [(name, cast(array))]
    if array.ndim == 1:
        return [(f"{name}[{i + 1}]", cast(x)) for i, x in enumerate(array)]
    return [(f"{name}[{i + 1},{j + 1}]", cast(array[i, j]))
            for i in range(array.shape[0]) for j in range(array.shape[1])]


def start_values(parameters: dict[str, Any]) -> dict[str, Any]:
    """fmpy start values of the FMI 2 FMU: one structured name per element (rows beyond
    the robot's joints keep the FMU's start values)."""
    return dict(pair for name, value in parameters.items() for pair in _elements(name, value))


def write_ssv(parameters: dict[str, object], path: str | Path, name: str = "robot") -> Path:
    """An SSP parameter set (SSV 1.0) of the parameters, FMI 2 names."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ssv:ParameterSet xmlns:ssv="{SSV}" version="1.0" '
             f'name={quoteattr(plain(name))}>',
             "  <ssv:Parameters>"]
    for key, value in start_values(parameters).items():
        kind = "Integer" if key.split("[")[0] in INTEGERS else "Real"
        text = str(value) if kind == "Integer" else repr(float(value))
        lines.append(f'    <ssv:Parameter name={quoteattr(key)}><ssv:{kind} value="{text}"/>'
                     f"</ssv:Parameter>")
    lines += ["  </ssv:Parameters>", "</ssv:ParameterSet>", ""]
    path = Path(path)
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


def read_ssv(path: str | Path) -> dict[str, float | int]:
    """The parameters of an SSV file as fmpy start values (FMI 2 names)."""
    from lxml import etree

    from ..inputs import xml_parser
    values = {}
    root = etree.parse(str(path), xml_parser()).getroot()
    for parameter in root.iter(f"{{{SSV}}}Parameter"):
        for child in parameter:
            kind = etree.QName(child).localname
            values[parameter.get("name")] = (int(child.get("value")) if kind == "Integer"
                                             else float(child.get("value")))
    return values


def run_fmu(fmu: str | Path, parameters: dict[str, Any], log: JointLog,
            statistics_interval: float = 0.0, samples_per_step: int = 1
            ) -> dict[str, np.ndarray]:
    """Replay the log through the RobotObserver FMU (FMI 2, fmpy), one communication step
    per `samples_per_step` samples: q and u of sample k are set, then doStep(t_k, s h)
    (the FMU holds them over its s internal steps).

    Returns {"velocity": qd_hat after each step (the estimate for t_k + s h, shape
    (N / s, n)),
    "velocity_sample": qd_sample (the estimate for t_k), "base_estimate", "base_std",
    "base_excitation" (at the end), "excitation", "gamma_trace"}."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    description = read_model_description(str(fmu))
    references = {v.name: v.valueReference for v in description.modelVariables}
    values = start_values({**parameters, "h": log.step,
                           "statistics_interval": statistics_interval})
    n, p = int(parameters["n"]), int(parameters["base_count"])
    q_refs = [references[f"q[{i + 1}]"] for i in range(n)]
    u_refs = [references[f"u[{i + 1}]"] for i in range(n)]
    qd_refs = [references[f"{name}[{i + 1}]"] for name in ("qd_hat", "qd_sample")
               for i in range(n)]
    unzipped = extract(str(fmu))
    slave = FMU2Slave(guid=description.guid, unzipDirectory=unzipped,
                      modelIdentifier=description.coSimulation.modelIdentifier,
                      instanceName="robot")
    slave.instantiate()
    try:
        integers = {k: v for k, v in values.items() if k.split("[")[0] in INTEGERS}
        reals = {k: v for k, v in values.items() if k not in integers}
        slave.setInteger([references[k] for k in integers], list(integers.values()))
        slave.setReal([references[k] for k in reals], list(reals.values()))
        slave.setupExperiment(startTime=float(log.t[0]))
        slave.enterInitializationMode()
        slave.setReal(q_refs + u_refs, [*log.q[0], *log.u[0]])
        slave.exitInitializationMode()
        starts = range(0, len(log.t) - samples_per_step + 1, samples_per_step)
        velocity = np.empty((len(starts), 2 * n))
        h = log.step
        for row, k in enumerate(starts):
            slave.setReal(q_refs + u_refs, [*log.q[k], *log.u[k]])
            slave.doStep(currentCommunicationPoint=float(log.t[0] + k * h),
                         communicationStepSize=samples_per_step * h)
            velocity[row] = slave.getReal(qd_refs)
        names = ("base_estimate", "base_std", "base_excitation")
        result = {"velocity": velocity[:, :n], "velocity_sample": velocity[:, n:]}
        for name in names:
            result[name] = np.array(slave.getReal([references[f"{name}[{k + 1}]"]
                                                   for k in range(p)]))
        result["gamma_trace"], result["excitation"] = slave.getReal(
            [references["gamma_trace"], references["excitation"]])
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    return result
