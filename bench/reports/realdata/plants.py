"""Pendulum trajectories made independently of the observer's discretization.

The plant is the paper's pendulum (section 6),

    J x'' = u - (M g L / 2) sin x - Vs x' - Ps sign(x') + J v(t) - J d(t) x',

i.e. x'' = b u - c1 sin x - c2 x' - c3 sign x' + v - d x' with b = 1/J and
c = [M g L / (2 J), Vs / J, Ps / J].  Every data set holds uniform samples of
time, the true state, the true acceleration, the input and the true v, d.

Data set A (open loop, multi-sine torque, start at rest) is made by four
"plant kinds": an event-located DOP853 reference, RK45 at two tolerances read
from its dense output (what a plant FMU from another tool delivers), and
explicit Euler at the sample step (the paper's discretization).  Data set B is
the paper's closed loop (harness scenarios) and its explicit-Euler replay.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from harness.scenarios import A_COULOMB, A_GRAVITY, A_VISCOUS, COMMUNICATION_STEP, SCENARIOS, J

B_TRUE = 1.0 / J
C_TRUE = (A_GRAVITY, A_VISCOUS, A_COULOMB)

OPEN_LOOP_DURATION = 40.0  # s
# Multi-sine torque u = J sum A_i sin(2 pi f_i t + phase_i): incommensurate
# frequencies in 0.2-3 Hz; the amplitudes (rad/s^2) swing the pendulum to about
# +-1 rad (95th percentile 0.8 rad) with about 120 velocity reversals in 40 s.
# The slowest line sits below the natural frequency (0.37 Hz) on purpose: it
# keeps the swing large without resonating the pendulum over the top.
MULTISINE_FREQUENCIES = (0.23, 0.61, 1.37, 2.71)  # Hz
MULTISINE_AMPLITUDES = (2.0, 2.0, 5.0, 10.0)  # rad/s^2 (times J gives N m)
MULTISINE_PHASES = (0.3, 1.9, 4.1, 5.3)  # rad

PLANT_KINDS = ("accurate", "rk45-1e-4", "rk45-1e-6", "euler")
# The open-loop functions below take the torque, the coefficients and a damping d(t)
# (a function of time, None for d = 0); the defaults make data set A.
Signal = Callable[[np.ndarray | float], np.ndarray]
RK45_TOLERANCES = {"rk45-1e-4": (1e-4, 1e-8), "rk45-1e-6": (1e-6, 1e-10)}
STUCK_MAX_STEP = 1e-3  # s: open_loop_accurate's largest step while stuck
STOP_SPEED = 1e-6  # rad/s: open_loop_rk45's stop into static friction (stop_after)


@dataclass
class Dataset:
    """Uniform samples of one plant trajectory and its truth."""

    name: str  # "A" or a scenario name
    kind: str  # one of PLANT_KINDS
    t: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    acc: np.ndarray  # true acceleration over the interval starting at t (u held there)
    u: np.ndarray
    v: np.ndarray  # true disturbance v(t)
    d: np.ndarray  # true time-varying damping d(t)
    b: float = B_TRUE
    c: tuple[float, ...] = C_TRUE  # true c1, c2, c3 (d(t) aside)
    meta: dict[str, float | str] = field(default_factory=dict)

    @property
    def step(self) -> float:
        return float(self.t[1] - self.t[0])

    def decimate(self, factor: int) -> Dataset:
        """Every factor-th sample: the same trajectory sampled more slowly (not for euler)."""
        s = slice(None, None, factor)
        return Dataset(self.name, self.kind, self.t[s], self.x1[s], self.x2[s], self.acc[s],
                       self.u[s], self.v[s], self.d[s], self.b, self.c, dict(self.meta))

    def save(self, path: Path) -> None:
        np.savez(path, t=self.t, x1=self.x1, x2=self.x2, acc=self.acc, u=self.u, v=self.v,
                 d=self.d, b=self.b, c=np.array(self.c), name=self.name, kind=self.kind)

    @staticmethod
    def load(path: Path) -> Dataset:
        z = np.load(path)
        return Dataset(str(z["name"]), str(z["kind"]), z["t"], z["x1"], z["x2"], z["acc"],
                       z["u"], z["v"], z["d"], float(z["b"]), tuple(float(c) for c in z["c"]))


def multisine(t: np.ndarray | float) -> np.ndarray:
    """The open-loop torque u(t) [N m]."""
    t = np.asarray(t, dtype=float)
    out = np.zeros_like(t)
    for f, a, p in zip(MULTISINE_FREQUENCIES, MULTISINE_AMPLITUDES, MULTISINE_PHASES):
        out += J * a * np.sin(2 * math.pi * f * t + p)
    return out


def _open_loop_acc(x1: np.ndarray, x2: np.ndarray, u: np.ndarray, sign: np.ndarray,
                   c: tuple[float, ...], d: np.ndarray, b: float = B_TRUE) -> np.ndarray:
    c1, c2, c3 = c[:3]
    return b * u - c1 * np.sin(x1) - c2 * x2 - c3 * sign - d * x2


def _damping_of(damping: Signal | None) -> Callable[[float], float]:
    return (lambda t: 0.0) if damping is None else (lambda t: float(damping(t)))


def _damping_samples(damping: Signal | None, t: np.ndarray) -> np.ndarray:
    return np.zeros_like(t) if damping is None else np.asarray(damping(t), dtype=float)


@dataclass
class _Event:
    """A solve_ivp event function with the attributes that solve_ivp reads off it:
    ``terminal`` (stop the integration there) and ``direction`` (the zero crossing's sign)."""

    function: Callable[[float, ArrayLike], float]
    terminal: bool = False
    direction: float = 0.0

    def __call__(self, t: float, x: ArrayLike) -> float:
        return self.function(t, x)


def _sample_times(rate: float, duration: float) -> np.ndarray:
    return np.arange(int(round(duration * rate))) / rate


def open_loop_accurate(rate: float, duration: float = OPEN_LOOP_DURATION, *,
                       torque: Signal = multisine, c: tuple[float, ...] = C_TRUE,
                       damping: Signal | None = None, breaks: tuple[float, ...] = (),
                       b: float = B_TRUE, name: str = "A") -> Dataset:
    """DOP853 at rtol = atol = 1e-12 with the Coulomb friction handled exactly.

    The velocity sign is a mode s in {-1, 0, +1}; a terminal event at x' = 0
    ends each mode, and at the reversal the pendulum either continues with the
    opposite sign or sticks (Filippov: |b u - c1 sin x| <= c3) until the driving
    acceleration exceeds the static friction.  No step crosses a discontinuity:
    the integration also stops at the ``breaks`` (the times where the torque or the
    damping jumps or kinks).
    """
    c1, c2, c3 = c[:3]
    d_of = _damping_of(damping)
    t_samples = _sample_times(rate, duration)

    def drive(t: float, x1: float) -> float:  # acceleration without the friction terms
        return b * float(torque(t)) - c1 * math.sin(x1)

    def mode_of(t: float, x1: float) -> int:
        f0 = drive(t, x1)
        return int(np.sign(f0)) if abs(f0) > c3 else 0

    segments: list[tuple[float, float, Callable[[np.ndarray], np.ndarray], int]] = []
    t0, state, mode = 0.0, np.array([0.0, 0.0]), mode_of(0.0, 0.0)
    end = float(t_samples[-1]) + 1e-9
    while t0 < end:
        if mode == 0:
            x_stuck = float(state[0])

            def rhs(t, x):  # noqa: ANN001 -- stuck: nothing moves
                return [0.0, 0.0]

            def event(t, x):  # noqa: ANN001 -- breakaway when the drive beats static friction
                return abs(drive(t, x_stuck)) - c3  # noqa: B023 (called in this iteration)
            direction = 1
        else:
            s = mode

            def rhs(t, x):  # noqa: ANN001
                return [x[1], drive(t, x[0]) - (c2 + d_of(t)) * x[1] - c3 * s]  # noqa: B023 (called in this iteration)

            def event(t, x):  # noqa: ANN001 -- velocity reversal
                return x[1]
            direction = -s
        stop = min([b for b in breaks if t0 < b < end] + [end])
        # Stuck, nothing moves and the solver's steps grow without bound: cap them so
        # that the breakaway event cannot fall between two steps (a long stick).
        sol = solve_ivp(rhs, (t0, stop), state, method="DOP853", rtol=1e-12, atol=1e-12,
                        events=_Event(event, terminal=True, direction=direction),
                        dense_output=True,
                        max_step=STUCK_MAX_STEP if mode == 0 else math.inf)
        t1 = float(sol.t[-1])
        segments.append((t0, t1, sol.sol, mode))
        if sol.status != 1:  # reached a break or the end
            if stop >= end:
                break
            state, t0 = sol.y[:, -1].copy(), stop
            if mode == 0:  # stuck through a jump of the drive: it may now break away
                mode = mode_of(t0, float(state[0]))
            continue
        state = np.array([sol.y[0, -1], 0.0])
        f0 = drive(t1, float(state[0]))
        if mode == 0:  # breakaway: |f0| = c3 at the event, move the way the drive pushes
            mode = 1 if f0 >= 0 else -1
        else:  # reversal: continue backwards if the drive beats static friction, else stick
            new = mode_of(t1, float(state[0]))
            mode = new if new == -mode else 0
        t0 = t1
        if len(segments) > 100000:
            raise RuntimeError("open_loop_accurate: more than 1e5 friction mode changes")
    x1, x2, sign = (np.empty_like(t_samples) for _ in range(3))
    starts = np.array([s[0] for s in segments])
    which = np.clip(np.searchsorted(starts, t_samples, side="right") - 1, 0, len(segments) - 1)
    for i, (_, _, dense, m) in enumerate(segments):
        sel = which == i
        if np.any(sel):
            x = dense(t_samples[sel])
            x1[sel], x2[sel], sign[sel] = x[0], (x[1] if m else 0.0), m
    u = torque(t_samples)
    d = _damping_samples(damping, t_samples)
    acc = np.where(sign == 0, 0.0, _open_loop_acc(x1, x2, u, sign, c, d, b))
    return Dataset(name, "accurate", t_samples, x1, x2, acc, u, np.zeros_like(t_samples), d,
                   b=b, c=tuple(c[:3]), meta={"segments": len(segments),
                         "stuck_segments": sum(1 for s in segments if s[3] == 0)})


def open_loop_rk45(kind: str, rate: float, duration: float = OPEN_LOOP_DURATION, *,
                   torque: Signal = multisine, c: tuple[float, ...] = C_TRUE,
                   damping: Signal | None = None, stop_after: float | None = None) -> Dataset:
    """RK45 with the kind's tolerances and no event handling, read from its dense output
    (it steps across the Coulomb friction's and the torque's jumps like any solver
    without events).

    ``stop_after``: from then on, the pendulum stops where its speed falls below
    STOP_SPEED inside the static-friction band (|b u - c1 sin x| <= c3): it sticks
    there and rests.  Without events a solver slides along x' = 0 at steps of about
    1e-7 s (measured for RK45 at rtol 1e-4: a creeping speed of 1e-7 to 1e-6 rad/s),
    too many to integrate here; from the stop to x' = 0 the angle moves by about
    STOP_SPEED^2 / (2 c3), far below any sensor's resolution.
    """
    rtol, atol = RK45_TOLERANCES[kind]
    c1, c2, c3 = c[:3]
    d_of = _damping_of(damping)
    t_samples = _sample_times(rate, duration)
    t_end = float(t_samples[-1])

    def rhs(t, x):  # noqa: ANN001
        return [x[1], B_TRUE * float(torque(t)) - c1 * math.sin(x[0]) - (c2 + d_of(t)) * x[1]
                - c3 * float(np.sign(x[1]))]

    def stop_speed(t, x):  # noqa: ANN001 -- |x'| falls below STOP_SPEED inside the band
        held = abs(B_TRUE * float(torque(t)) - c1 * math.sin(x[0])) <= c3
        return abs(x[1]) - STOP_SPEED if held else abs(x[1]) + 1.0
    stop = _Event(stop_speed, terminal=True, direction=-1)

    def solve(t0: float, x0: list[float], t1: float, events=None):  # noqa: ANN001, ANN202
        return solve_ivp(rhs, (t0, t1), x0, method="RK45", rtol=rtol, atol=atol,
                         dense_output=True, events=events)

    first = stop_after if stop_after is not None and stop_after < t_end else t_end
    pieces = [solve(0.0, [0.0, 0.0], first)]
    rest: tuple[float, float] | None = None  # (time, angle) where the pendulum sticks
    if first < t_end:
        x0 = [float(v) for v in pieces[-1].y[:, -1]]
        if stop(first, x0) < 0:  # already resting
            rest = (first, x0[0])
        else:
            pieces.append(solve(first, x0, t_end, stop))
            if pieces[-1].status == 1:
                rest = (float(pieces[-1].t[-1]), float(pieces[-1].y[0, -1]))
    x = np.zeros((2, len(t_samples)))
    starts = np.array([float(p.t[0]) for p in pieces])
    which = np.clip(np.searchsorted(starts, t_samples, side="right") - 1, 0, len(pieces) - 1)
    for i, piece in enumerate(pieces):
        sel = which == i
        if np.any(sel):
            x[:, sel] = piece.sol(t_samples[sel])
    if rest is not None:
        after = t_samples >= rest[0]
        x[0, after], x[1, after] = rest[1], 0.0
    u = torque(t_samples)
    d = _damping_samples(damping, t_samples)
    acc = _open_loop_acc(x[0], x[1], u, np.sign(x[1]), c, d)
    meta: dict[str, float | str] = {"nfev": int(sum(p.nfev for p in pieces))}
    if rest is not None:
        meta["rest_from"] = rest[0]
    return Dataset("A", kind, t_samples, x[0], x[1], acc, u, np.zeros_like(t_samples), d,
                   c=tuple(c[:3]), meta=meta)


def _euler(t: np.ndarray, u: np.ndarray, v: np.ndarray, d: np.ndarray, c: tuple[float, ...],
           x0: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Explicit Euler x_{k+1} = x_k + h f(t_k, x_k, u_k) with sign(0) = 0: plain loop (cheap)."""
    h = float(t[1] - t[0])
    c1, c2, c3 = c
    b = B_TRUE
    n = len(t)
    x1, x2, acc = np.empty(n), np.empty(n), np.empty(n)
    p, w = x0
    uu, vv, dd = u.tolist(), v.tolist(), d.tolist()
    sin = math.sin
    for k in range(n):
        a = b * uu[k] - c1 * sin(p) - c2 * w - c3 * ((w > 0) - (w < 0)) + vv[k] - dd[k] * w
        x1[k], x2[k], acc[k] = p, w, a
        p, w = p + h * w, w + h * a
    return x1, x2, acc


def open_loop_euler(rate: float, duration: float = OPEN_LOOP_DURATION, *,
                    torque: Signal = multisine, c: tuple[float, ...] = C_TRUE,
                    damping: Signal | None = None) -> Dataset:
    """Explicit Euler at the sample step with u held per sample (the paper's discretization)."""
    t = _sample_times(rate, duration)
    u = torque(t)
    d = _damping_samples(damping, t)
    x1, x2, acc = _euler(t, u, np.zeros_like(t), d, c, (0.0, 0.0))
    return Dataset("A", "euler", t, x1, x2, acc, u, np.zeros_like(t), d, c=tuple(c[:3]))


def closed_loop_accurate(scenario: str, fmu_dir: Path) -> Dataset:
    """The harness closed loop (Pendulum FMU: RK4 at 1e-5 s, sampled at 1e-4 s)."""
    from harness.scenarios import run_scenario

    s = SCENARIOS[scenario]
    r = run_scenario(s, fmu_dir)
    t, x1, x2 = r.time, r["plant.theta"], r["plant.omega"]
    u, v, d = r["controller.u"], r["plant.v"], r["plant.d"]
    c = tuple(s.c_true[:3])
    # The FMU's own acceleration output uses the previous sample's u; recompute it
    # with u_k, the input held over [t_k, t_k+1], as for every other data set.
    acc = B_TRUE * u - c[0] * np.sin(x1) - c[1] * x2 - c[2] * np.sign(x2) + v - d * x2
    return Dataset(scenario, "accurate", t, x1, x2, acc, u, v, d, B_TRUE, c)


def closed_loop_euler(accurate: Dataset) -> Dataset:
    """Explicit Euler at 1e-4 s of the same pendulum driven by the recorded u (held per sample)
    and the scenario's v(t), d(t): an open-loop replay, so its path differs slightly."""
    s = SCENARIOS[accurate.name]
    x0 = (float(s.plant["theta_start"]), float(s.plant["omega_start"]))
    assert abs(accurate.step - COMMUNICATION_STEP) < 1e-12
    x1, x2, acc = _euler(accurate.t, accurate.u, accurate.v, accurate.d, accurate.c, x0)
    return Dataset(accurate.name, "euler", accurate.t.copy(), x1, x2, acc, accurate.u.copy(),
                   accurate.v.copy(), accurate.d.copy(), accurate.b, accurate.c)


def make(name: str, kind: str, rate: float, fmu_dir: Path) -> Dataset:
    """The data set (name, kind) at the sample rate; variable-step kinds only for A."""
    if name == "A":
        if kind == "euler":
            return open_loop_euler(rate)
        factor = int(round(10000 / rate))  # one trajectory, sampled at 10 kHz and decimated
        base = open_loop_accurate(10000) if kind == "accurate" else open_loop_rk45(kind, 10000)
        return base.decimate(factor) if factor > 1 else base
    if rate != 1 / COMMUNICATION_STEP:
        raise ValueError(f"closed-loop data exist at 10 kHz only, not {rate} Hz")
    accurate = closed_loop_accurate(name, fmu_dir)
    if kind == "accurate":
        return accurate
    if kind == "euler":
        return closed_loop_euler(accurate)
    raise ValueError(f"plant kind {kind!r} is not made for the closed loop {name}")
