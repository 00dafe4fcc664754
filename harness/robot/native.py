"""The C rigid-body core (fmu/src/core/rigid_body.c) for the harness, through ctypes.

The batch entry points (native/robot_native.c) live in the package's native library
(`harness.native_library`), built with the package from the same core objects as the
RobotObserver FMU.
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..native_library import load_library
from .layout import ParameterLayout

_double_p = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_int_p = np.ctypeslib.ndpointer(dtype=np.int32, flags="C_CONTIGUOUS")


@lru_cache(maxsize=1)
def load() -> ctypes.CDLL:
    """The rigid-body entry points of the native library, typed."""
    dll = load_library()
    dll.rn_model_size.restype = ctypes.c_size_t
    dll.rn_max_joints.restype = ctypes.c_int
    dll.rn_load.restype = ctypes.c_int
    dll.rn_load.argtypes = [ctypes.c_void_p, ctypes.c_int, _int_p, _double_p, _double_p,
                            _double_p, _double_p, _double_p, _double_p, ctypes.c_double]
    count = ctypes.c_long
    dll.rn_inverse_dynamics.argtypes = [ctypes.c_void_p, count, _double_p, _double_p, _double_p,
                                        ctypes.c_int, ctypes.c_int, _double_p]
    dll.rn_gravity.argtypes = [ctypes.c_void_p, count, _double_p, _double_p]
    dll.rn_coriolis.argtypes = [ctypes.c_void_p, count, _double_p, _double_p, _double_p]
    dll.rn_mass_matrix.argtypes = [ctypes.c_void_p, count, _double_p, _double_p]
    dll.rn_forward_dynamics.restype = ctypes.c_long
    dll.rn_forward_dynamics.argtypes = [ctypes.c_void_p, count, _double_p, _double_p, _double_p,
                                        _double_p]
    dll.rn_regressor.argtypes = [ctypes.c_void_p, count, _double_p, _double_p, _double_p,
                                 _double_p]
    dll.rn_identifier_size.restype = ctypes.c_size_t
    dll.rn_identify.restype = ctypes.c_int
    dll.rn_identify.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int, ctypes.c_int,
                                _int_p, _double_p, ctypes.c_double, ctypes.c_double,
                                ctypes.c_double, count, _double_p, _double_p, _double_p,
                                _double_p, ctypes.c_long, _double_p, _double_p, _double_p]
    dll.rn_adaptive_size.restype = ctypes.c_size_t
    dll.rn_observe_adaptive.restype = ctypes.c_int
    dll.rn_observe_adaptive.argtypes = [ctypes.c_void_p, ctypes.c_int, count, ctypes.c_double,
                                        _double_p, ctypes.c_void_p, _double_p, ctypes.c_double,
                                        _double_p, _double_p, _double_p, _double_p,
                                        ctypes.c_void_p]
    dll.rn_robot_run_size.restype = ctypes.c_size_t
    dll.rn_settings_size.restype = ctypes.c_size_t
    if dll.rn_settings_size() != ctypes.sizeof(RobotSettings):
        raise RuntimeError("the native library's RobotSettings (fmu/src/core/robot_pipeline.h) "
                           "does not match harness/robot/native.py's: rebuild the library")
    dll.rn_default_settings.argtypes = [ctypes.c_int, ctypes.POINTER(RobotSettings)]
    dll.rn_robot_observe.restype = ctypes.c_long
    dll.rn_robot_observe.argtypes = [
        ctypes.c_void_p, ctypes.c_void_p, ctypes.POINTER(RobotSettings), count, count,
        _double_p, _double_p, _double_p, _double_p, _double_p, _double_p, _double_p, _double_p,
        _double_p, _double_p]
    return dll


#: RB_MAX_JOINTS of the native library (cmake/native.cmake's STO_NATIVE_MAX_JOINTS; the
#: FMUs keep 7), checked against the library by the Structure's size
_JOINTS = 12
_PARAMETERS = 12 * _JOINTS  # RRI_MAX_PARAMETERS


#: RobotSettings.regression by name (fmu/src/core/robot_observer.h's RoRegression)
REGRESSIONS = {"observer": 0, "window": 1}


class RobotSettings(ctypes.Structure):
    """fmu/src/core/robot_pipeline.h's RobotSettings, field for field: how the robot
    pipeline is set up (the RobotObserver FMU's parameters)."""

    _fields_ = [
        ("n", ctypes.c_int), ("identifier", ctypes.c_int), ("regression", ctypes.c_int),
        ("p", ctypes.c_int),
        ("columns", ctypes.c_int * _PARAMETERS),
        ("h", ctypes.c_double), ("tau", ctypes.c_double),
        ("convergence_window", ctypes.c_double), ("gain_exponent", ctypes.c_double),
        ("rho", ctypes.c_double), ("R", ctypes.c_double),
        ("min_speed", ctypes.c_double), ("reversal_margin", ctypes.c_double),
        ("statistics_interval", ctypes.c_double),
        ("f_plus", ctypes.c_double * _JOINTS), ("alpha1", ctypes.c_double * _JOINTS),
        ("alpha2", ctypes.c_double * _JOINTS), ("torque_scale", ctypes.c_double * _JOINTS),
    ]


def default_settings(n: int) -> RobotSettings:
    """The C core's defaults (fmu/src/core/tuning.h) for n joints, nothing identified."""
    settings = RobotSettings()
    load().rn_default_settings(n, ctypes.byref(settings))
    return settings


@dataclass(frozen=True)
class CoreDefaults:
    """The C core's defaults the harness shares (fmu/src/core/tuning.h, rigid_body.h),
    read from the library so that Python keeps no copy of them."""

    min_speed: float            # [rad/s or m/s] joint equations slower than this left out
    reversal_margin: float      # [s] and for this long after a reversal
    statistics_interval: float  # [s] between the solves with standard errors
    max_joints: int             # joints of a serial robot at most


@lru_cache(maxsize=1)
def core_defaults() -> CoreDefaults:
    """The defaults of the native library in use."""
    settings = default_settings(1)
    return CoreDefaults(settings.min_speed, settings.reversal_margin,
                        settings.statistics_interval, int(load().rn_max_joints()))


@dataclass
class AdaptiveVelocities:
    """What observe_adaptive gives per sample and joint, arrays (count, n)."""

    velocity: np.ndarray      # the published velocity estimate at the sample
    acceleration: np.ndarray  # the published perturbation: without a model, q''
    noise: np.ndarray         # the estimated measurement noise std [rad or m]
    bandwidth: np.ndarray     # of the published observer [rad/s] (1/h: super-twisting)
    position: np.ndarray | None = None  # its corrected position at the sample (if asked)


def observe_adaptive(q: np.ndarray, h: float, acceleration_bound, tau: float = 0.002,
                     nominal: np.ndarray | None = None,
                     with_position: bool = False) -> AdaptiveVelocities:
    """Each joint's positions q (count, n) sampled every h through the observer FMU's
    default estimator without a model: the implicit super-twisting observer beside the
    bank of noise-adaptive linear observers (fmu/src/core/noise_adaptive.c), which
    estimates the measurement noise itself and publishes the observer that fits it.
    Causal: the estimate at a sample uses the measurements up to it.
    acceleration_bound (per joint) bounds |q''| (Theorem 3.1 gains of the
    super-twisting observer); tau filters its injection (the FMU's default 2 ms).
    nominal (count, n), if given, is a known acceleration held over the interval that
    starts at each sample (the FMU's F input); without it the observer is model-free.
    with_position: also the published observer's corrected position at each sample."""
    q = np.ascontiguousarray(np.atleast_2d(q), dtype=np.float64)
    count, n = q.shape
    bound = np.ascontiguousarray(np.broadcast_to(np.asarray(acceleration_bound, float), (n,)))
    out = [np.empty_like(q) for _ in range(4)]
    dll = load()
    bank = ctypes.create_string_buffer(dll.rn_adaptive_size())
    if nominal is not None:
        nominal = np.ascontiguousarray(np.broadcast_to(nominal, q.shape), dtype=np.float64)
    pointer = None if nominal is None else nominal.ctypes.data
    position = np.empty_like(q) if with_position else None
    if dll.rn_observe_adaptive(bank, n, count, h, q, pointer, bound, tau, *out,
                               None if position is None else position.ctypes.data) != 0:
        raise ValueError(f"no observer gains for the acceleration bounds {bound.tolist()}")
    velocity, acceleration, noise, bandwidth = out
    return AdaptiveVelocities(velocity, acceleration, noise, bandwidth, position)


STATUS = {-1: f"the number of joints is not between 1 and {_JOINTS}",
          -2: "a joint type is neither revolute nor prismatic",
          -3: "a joint axis is zero or not finite",
          -4: "a placement, inertial, friction or gravity value is not finite"}


def _samples(x: np.ndarray, n: int) -> np.ndarray:
    """Samples as a C-contiguous (count, n) float array (one sample may be 1-D)."""
    array = np.ascontiguousarray(np.atleast_2d(np.asarray(x, dtype=np.float64)))
    if array.shape[1] != n:
        raise ValueError(f"expected {n} joint values per sample, got {array.shape[1]}")
    return array


class RigidBody:
    """The C model of a serial chain, built from the flat arrays of rigid_body.h.

    All methods take samples as arrays (count, n) (or one sample (n,)) and return
    arrays with a leading sample axis."""

    def __init__(self, types, axis, xyz, rpy, link, friction, gravity=(0.0, 0.0, -9.81),
                 coulomb_velocity: float = 0.0):
        dll = load()
        self.n = len(types)
        self._buffer = ctypes.create_string_buffer(dll.rn_model_size())
        flat = [np.ascontiguousarray(np.asarray(a, dtype=np.float64).ravel())
                for a in (axis, xyz, rpy, link, friction, gravity)]
        status = dll.rn_load(self._buffer, self.n, np.ascontiguousarray(types, dtype=np.int32),
                             *flat, float(coulomb_velocity))
        if status != 0:
            raise ValueError(f"rigid-body model rejected: {STATUS.get(status, status)}")
        self.parameter_count = ParameterLayout(self.n).standard_size

    def inverse_dynamics(self, q, qd, qdd, gravity: bool = True,
                         friction: bool = True) -> np.ndarray:
        q, qd, qdd = (_samples(x, self.n) for x in (q, qd, qdd))
        tau = np.empty_like(q)
        load().rn_inverse_dynamics(self._buffer, len(q), q, qd, qdd, int(gravity), int(friction),
                                   tau)
        return tau

    def gravity(self, q) -> np.ndarray:
        q = _samples(q, self.n)
        g = np.empty_like(q)
        load().rn_gravity(self._buffer, len(q), q, g)
        return g

    def coriolis(self, q, qd) -> np.ndarray:
        q, qd = _samples(q, self.n), _samples(qd, self.n)
        c = np.empty_like(q)
        load().rn_coriolis(self._buffer, len(q), q, qd, c)
        return c

    def mass_matrix(self, q) -> np.ndarray:
        q = _samples(q, self.n)
        M = np.empty((len(q), self.n, self.n))
        load().rn_mass_matrix(self._buffer, len(q), q, M)
        return M

    def forward_dynamics(self, q, qd, tau) -> np.ndarray:
        q, qd, tau = (_samples(x, self.n) for x in (q, qd, tau))
        qdd = np.empty_like(q)
        if load().rn_forward_dynamics(self._buffer, len(q), q, qd, tau, qdd):
            raise ValueError("the inertia matrix is not positive definite (non-physical "
                             "inertial parameters)")
        return qdd

    def identify_online(self, columns, q, qd, qdd, tau, h: float, kind: str = "lsm",
                        rho: float = 1e-6, R: float = 0.1, torque_scale=None,
                        reset_at: int = -1) -> dict:
        """Run the C online identifier (regressor_identifier.c) over the samples.

        The model is the nominal one; returns {"delta": beta - beta_nominal over the
        base `columns`, "std_error", "gamma_trace", "excitation"}; the identifier is
        reset before sample `reset_at` (-1: never)."""
        dll = load()
        q, qd, qdd, tau = (_samples(x, self.n) for x in (q, qd, qdd, tau))
        columns = np.ascontiguousarray(columns, dtype=np.int32)
        scale = np.ones(self.n) if torque_scale is None else np.asarray(torque_scale, float)
        delta, std, stats = np.zeros(len(columns)), np.zeros(len(columns)), np.zeros(2)
        state = ctypes.create_string_buffer(dll.rn_identifier_size())
        status = dll.rn_identify(self._buffer, state, {"lsm": 1, "mff": 2}[kind], len(columns),
                                 columns, np.ascontiguousarray(scale), h, rho, R, len(q), q,
                                 qd, qdd, tau, reset_at, delta, std, stats)
        if status != 0:
            raise ValueError("online identifier rejected its settings (columns, h, rho, R or "
                             "torque scales out of range)")
        return {"delta": delta, "std_error": std, "gamma_trace": stats[0],
                "excitation": stats[1]}

    def observe(self, q, u, h: float, f_plus, tau: float | None = None, alpha1=0.0, alpha2=0.0,
                identify: dict | None = None) -> dict:
        """Run the model-based observer of robot_observer.c over positions q and torques u
        (count, n) sampled every h, as the RobotObserver FMU does: f_plus (per joint)
        bounds the model's acceleration error, gains alpha1, alpha2 left at 0 follow from
        it by Theorem 3.1 (p = 0.5); tau is the injection's and the regression's filter
        (default the FMU's).

        Returns {"velocity": the estimate at each sample, "prediction": for the end of
        the interval starting at each sample, "model_failures": samples at which M was
        not positive definite, "weight": the weight (0 or 1) of each sample's joint
        equations in the regression (NaN where none was taken), "acceleration": the
        observer's q'' at each sample (the last sample's NaN)}.  With identify =
        {"columns", "kind" ("lsm"/"mff"), "regression" ("window", the FMU's default: a
        zero-phase window's derivatives a fixed lag behind; "observer": the observer's
        estimates), "rho", "R", "torque_scale", "start" (sample index), "min_speed",
        "reversal_margin"} (defaults the FMU's) the online identifier
        runs too, adding "delta" (base parameters minus the nominal ones), "std_error",
        "gamma_trace" and "excitation" at the end, and "published": what the FMU
        publishes after the last sample (identify's "statistics_interval", default
        core_defaults(): the solves with standard errors spread over the samples after
        each snapshot,
        fmu/src/core/statistics_job.h) as {"delta", "std_error", "gamma_trace",
        "excitation"}.  Joint i's equation weighs 0 where |q_i'| < min_speed
        (rad/s or m/s, default core_defaults()), where q_i' reverses, and for reversal_margin
        seconds after (default core_defaults(); through the window also for 1.5 periods of
        its cut-off on both sides); both 0: every equation is used."""
        dll = load()
        q, u = _samples(q, self.n), _samples(u, self.n)
        n = self.n
        settings = default_settings(n)
        settings.h = h
        if tau is not None:
            settings.tau = tau
        for name, value in (("alpha1", alpha1), ("alpha2", alpha2), ("f_plus", f_plus)):
            getattr(settings, name)[:n] = np.broadcast_to(np.asarray(value, float), (n,)).tolist()
        velocity, prediction = np.empty_like(q), np.empty_like(q)
        weight, acceleration = np.empty_like(q), np.empty_like(q)
        options = dict(identify or {})
        for name in ("min_speed", "reversal_margin", "statistics_interval", "rho", "R"):
            if name in options:
                setattr(settings, name, float(options[name]))
        if "regression" in options:
            settings.regression = REGRESSIONS[options["regression"]]
        columns = np.ascontiguousarray(options.get("columns", [0]), dtype=np.int32)
        if len(columns) > _PARAMETERS:
            raise ValueError(f"{len(columns)} base columns: the identifier takes at most "
                             f"{_PARAMETERS}")
        settings.p = len(columns)
        settings.columns[:len(columns)] = columns.tolist()
        scale = options.get("torque_scale")
        if scale is not None:
            settings.torque_scale[:n] = np.broadcast_to(np.asarray(scale, float), (n,)).tolist()
        settings.identifier = {"lsm": 1, "mff": 2}[options.get("kind", "lsm")] if identify else 0
        delta, std, stats = np.zeros(len(columns)), np.zeros(len(columns)), np.zeros(2)
        published = np.zeros(3 * len(columns) + 2)
        run = ctypes.create_string_buffer(dll.rn_robot_run_size())
        failures = dll.rn_robot_observe(
            self._buffer, run, ctypes.byref(settings), len(q), int(options.get("start", 0)), q, u,
            velocity, prediction, weight, acceleration, delta, std, stats, published)
        rule = (settings.min_speed, settings.reversal_margin)
        if failures == -2:
            raise ValueError(f"no observer gains for f_plus {list(settings.f_plus[:n])}")
        if failures == -3:
            raise ValueError("the observer diverged (estimates not finite): the model's "
                             "acceleration error exceeds what the gains correct; raise f_plus")
        if failures == -4:
            raise ValueError(f"min_speed {rule[0]!r} and reversal_margin {rule[1]!r} must be "
                             f"finite and >= 0")
        if failures < 0:
            raise ValueError("online identifier rejected its settings (columns, h, rho, R or "
                             "torque scales out of range)")
        result = {"velocity": velocity, "prediction": prediction, "model_failures": failures,
                  "weight": weight, "acceleration": acceleration}
        if identify:
            p = len(columns)
            result.update(delta=delta, std_error=std, gamma_trace=stats[0], excitation=stats[1],
                          published={"delta": published[:p], "std_error": published[p:2 * p],
                                     "gamma_trace": published[2 * p],
                                     "excitation": published[2 * p + 1],
                                     "column_excitation": published[2 * p + 2:]})
        return result

    def regressor(self, q, qd, qdd) -> np.ndarray:
        """Y with tau = Y pi: shape (count, n, 12 n), pi = 10 link parameters per link,
        then (viscous, Coulomb) per joint."""
        q, qd, qdd = (_samples(x, self.n) for x in (q, qd, qdd))
        Y = np.empty((len(q), self.n, self.parameter_count))
        load().rn_regressor(self._buffer, len(q), q, qd, qdd, Y)
        return Y
