"""Held-out joints: plant data the FMU's defaults were never tuned on.

The defaults (gains, filters, the velocity bank, tau_identifier) were chosen on
data set A and the paper's loops, all one pendulum.  These three joints keep the
FMU's model structure, x'' = b u - c1 sin x - c2 x' - c3 sign x', but change
every scale the defaults could have been fitted to: the inertia over three
decades, the natural frequency, the share of friction, the excitation's band and
shape.  They are integrated like A's `accurate` kind (DOP853 1e-12, every
reversal and stick located) at 10 kHz and sampled at 1, 2, 5 and 10 kHz (2 and
5 kHz: rates no default was tuned at), measured by sensors partly absent from
the tuning grid (14- and 18-bit encoders, a 16-bit encoder whose counts jitter),
and given a nominal model 10 % off in inertia with the friction guessed at half.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import plants
from .plants import Dataset, Signal

DURATION = 40.0  # s, as data set A
SIMULATION_RATE = 10000  # Hz: every rate decimates this one trajectory
RATES = (1000, 2000, 5000, 10000)
MEASUREMENTS = ("clean", "noise-1e-5", "noise-1e-4", "enc-14", "enc-18", "enc-16+noise-1e-4")
PHASES = (0.3, 1.9, 4.1, 5.3)  # rad, the multi-sines' (A's)


@dataclass(frozen=True)
class HeldOutPlant:
    """One joint: b = 1/J, c = (c1, c2, c3) and its torque u(t) [N m]."""

    name: str
    description: str
    b: float
    c: tuple[float, float, float]
    torque: Signal


def multisine(frequencies: tuple[float, ...], amplitudes: tuple[float, ...], b: float) -> Signal:
    """u = J sum A_i sin(2 pi f_i t + phase_i), A_i in rad/s^2."""
    def u(t: np.ndarray | float) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        out = np.zeros_like(t)
        for f, a, p in zip(frequencies, amplitudes, PHASES):
            out += a / b * np.sin(2 * math.pi * f * t + p)
        return out
    return u


def chirp(f0: float, f1: float, amplitude: float, b: float) -> Signal:
    """A linear sweep f0 -> f1 over DURATION, acceleration amplitude rising as f^1.5
    (so that the swing shrinks slowly as the frequency climbs past resonance)."""
    def u(t: np.ndarray | float) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        f = f0 + (f1 - f0) * t / DURATION
        phase = 2 * math.pi * (f0 * t + (f1 - f0) * t ** 2 / (2 * DURATION))
        return amplitude / b * (1 + f ** 1.5) * np.sin(phase)
    return u


PLANTS: dict[str, HeldOutPlant] = {p.name: p for p in [
    # A light, fast joint: J = 2e-3 (A's is 0.89), natural frequency 1.2 Hz, excited up
    # to 9 Hz; swings +-0.65 rad with about 440 velocity reversals in 40 s.
    HeldOutPlant("C-fast", "light fast joint: b 500, c (60, 2, 8), multi-sine 0.9-8.9 Hz",
                 500.0, (60.0, 2.0, 8.0),
                 multisine((0.9, 2.3, 4.7, 8.9), (15.0, 25.0, 60.0, 150.0), 500.0)),
    # A heavy, slow joint whose Coulomb friction is large against its drive: it sticks
    # 11 times (5 % of the record) and reverses about 36 times; 0.07-0.97 Hz.
    HeldOutPlant("C-heavy", "heavy slow joint with stick-slip: b 0.4, c (4, 0.05, 1.2), "
                 "multi-sine 0.07-0.97 Hz", 0.4, (4.0, 0.05, 1.2),
                 multisine((0.07, 0.19, 0.43, 0.97), (1.5, 1.5, 2.5, 3.0), 0.4)),
    # A sweep instead of a stationary multi-sine: the swing falls from 0.6 rad (first
    # 10 s) to 0.05 rad (last 10 s) while the velocity stays about 1.5 rad/s, so the
    # gravity column is informative early only.
    HeldOutPlant("C-chirp", "medium joint under a chirp: b 20, c (15, 0.5, 2), "
                 "sweep 0.2-6 Hz", 20.0, (15.0, 0.5, 2.0), chirp(0.2, 6.0, 6.0, 20.0)),
]}


def make(name: str) -> Dataset:
    """The held-out joint's trajectory at SIMULATION_RATE (decimate it per rate)."""
    p = PLANTS[name]
    return plants.open_loop_accurate(SIMULATION_RATE, DURATION, torque=p.torque, c=p.c, b=p.b,
                                     name=name)
