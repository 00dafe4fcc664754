"""A lightly damped cubic (Duffing) oscillator measured near its bandwidth:

    m y'' + d y' + k y + k3 y^3 = u

resonance at 68 Hz (about fs/9 at 610 Hz), damping ratio 0.03, a broadband periodic
multisine input (0.5-150 Hz, random phases) and 0.5 % white noise on the measured output
(relative to its RMS). The truth is integrated here with classical Runge-Kutta at 8
sub-steps per sample on the exact multisine, independently of the harness's simulator;
:func:`free_run` scores any parameters with that same integrator on the exact input.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

RATE = 610.0
TRUTH = {"m": 1.0, "d": 25.6, "k": 1.826e5, "k3": 6.5e6}
NAMES = ("m", "d", "k", "k3")
PERIOD = 8192            # samples of one period of the multisine
BAND = (0.5, 150.0)      # [Hz]
OUTPUT_RMS = 0.05        # the input is scaled for about this output RMS
INPUT_GAIN = 0.25        # input RMS over OUTPUT_RMS k: about OUTPUT_RMS out
NOISE = 0.005            # output noise std relative to the output RMS
FINE = 8                 # truth sub-steps per sample

MODEL_TOML = """\
# A cubic oscillator: m y'' + d y' + k y + k3 y^3 = u
[model]
coordinates = ["y"]
inputs = ["u"]
equations = ["m*der(y,2) + d*der(y) + k*y + k3*y^3 = u"]

[parameters]
m  = { nominal = 1 }
d  = { nominal = 0 }
k  = { nominal = 0 }
k3 = { nominal = 0 }
"""


@dataclass(frozen=True)
class Log:
    t: np.ndarray
    y: np.ndarray            # measured (noisy)
    u: np.ndarray            # measured input (exact samples)
    u_fine: np.ndarray       # the input at every half truth sub-step
    y_true: np.ndarray
    yd_true: np.ndarray
    ydd_true: np.ndarray


def multisine(seed: int, samples: int) -> np.ndarray:
    """The periodic input at every half truth sub-step (2 FINE points per sample), unit
    RMS: an inverse FFT of a flat band with random phases (exact between samples)."""
    rng = np.random.default_rng(seed)
    points = PERIOD * 2 * FINE
    spectrum = np.zeros(points // 2 + 1, complex)
    f = np.fft.rfftfreq(points, 1.0 / (RATE * 2 * FINE))
    band = (f >= BAND[0]) & (f <= BAND[1])
    spectrum[band] = np.exp(2j * np.pi * rng.random(band.sum()))
    one = np.fft.irfft(spectrum, points)
    one /= np.sqrt(np.mean(one ** 2))
    need = 2 * FINE * (samples - 1) + 1
    return np.tile(one, need // points + 1)[:need]


def free_run(theta: np.ndarray, u_fine: np.ndarray, y0: float, yd0: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """y, y', y'' at every sample: Runge-Kutta at FINE sub-steps on the exact input."""
    m, d, k, k3 = (float(v) for v in theta)
    h = 1.0 / (RATE * FINE)
    u = u_fine.tolist()
    samples = (len(u) - 1) // (2 * FINE) + 1
    out_y, out_yd = np.empty(samples), np.empty(samples)
    y, yd = float(y0), float(yd0)
    out_y[0], out_yd[0] = y, yd
    for s in range(1, samples):
        for j in range(FINE):
            i = 2 * ((s - 1) * FINE + j)
            a1 = (u[i] - d * yd - k * y - k3 * y * y * y) / m
            y2, v2 = y + 0.5 * h * yd, yd + 0.5 * h * a1
            a2 = (u[i + 1] - d * v2 - k * y2 - k3 * y2 * y2 * y2) / m
            y3, v3 = y + 0.5 * h * v2, yd + 0.5 * h * a2
            a3 = (u[i + 1] - d * v3 - k * y3 - k3 * y3 * y3 * y3) / m
            y4, v4 = y + h * v3, yd + h * a3
            a4 = (u[i + 2] - d * v4 - k * y4 - k3 * y4 * y4 * y4) / m
            y += h / 6 * (yd + 2 * v2 + 2 * v3 + v4)
            yd += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        out_y[s], out_yd[s] = y, yd
    out_ydd = (u_fine[::2 * FINE] - d * out_yd - k * out_y - k3 * out_y ** 3) / m
    return out_y, out_yd, out_ydd


def make_log(seed: int, samples: int = 65_000) -> Log:
    """A measured log of the oscillator: the input scaled for OUTPUT_RMS, noise added."""
    theta = np.array([TRUTH[n] for n in NAMES])
    u_fine = multisine(seed, samples)
    u_fine = INPUT_GAIN * OUTPUT_RMS * TRUTH["k"] * u_fine
    y, yd, ydd = free_run(theta, u_fine, 0.0, 0.0)
    rng = np.random.default_rng(seed + 1000)
    measured = y + NOISE * np.sqrt(np.mean(y ** 2)) * rng.standard_normal(len(y))
    t = np.arange(samples) / RATE
    return Log(t, measured, u_fine[::2 * FINE].copy(), u_fine, y, yd, ydd)


def write(log: Log, csv_path, model_path=None) -> None:
    """The log as CSV (t, y, u), and the model file when a path is given."""
    np.savetxt(csv_path, np.column_stack([log.t, log.y, log.u]), delimiter=",",
               header="t,y,u", comments="", fmt="%.10g")
    if model_path is not None:
        with open(model_path, "w", encoding="utf-8") as handle:
            handle.write(MODEL_TOML)
