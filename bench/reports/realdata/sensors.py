"""Measurement corruption (what a real angle sensor delivers) and nominal-model errors.

Measurements: noise-free, white Gaussian noise of a given std (fixed seeds), or
an encoder with 2^bits counts per revolution (y = q round(x / q)).  Model
errors: the nominal model the FMU is given (b, c_nominal) is off from the truth
in a stated way.
"""
from __future__ import annotations

import math
import zlib
from dataclasses import dataclass

import numpy as np

R_MIN = 1e-14  # floor of the measurement variance given to the Kalman filters


@dataclass(frozen=True)
class Measurement:
    """One way of measuring the angle."""

    name: str
    noise_std: float = 0.0  # rad, white Gaussian
    bits: int = 0  # encoder resolution, 0 = none

    @property
    def quantum(self) -> float:
        return 2 * math.pi / 2 ** self.bits if self.bits else 0.0

    @property
    def variance(self) -> float:
        """The measurement error variance a Kalman filter should assume (floored at R_MIN):
        the noise variance, or q^2/12 of a uniform quantization error."""
        return max(self.noise_std ** 2 + self.quantum ** 2 / 12, R_MIN)

    @property
    def level(self) -> float:
        """Equivalent error std [rad] (the figure's abscissa)."""
        return math.sqrt(self.noise_std ** 2 + self.quantum ** 2 / 12)

    @property
    def label(self) -> str:
        noise = f"noise {self.noise_std:.0e}" if self.noise_std else ""
        if self.bits:
            return f"{self.bits}-bit encoder" + (f" + {noise}" if noise else "")
        return noise or "noise-free"


MEASUREMENTS: dict[str, Measurement] = {m.name: m for m in [
    Measurement("clean"),
    Measurement("noise-1e-6", noise_std=1e-6),
    Measurement("noise-1e-5", noise_std=1e-5),
    Measurement("noise-1e-4", noise_std=1e-4),
    Measurement("noise-1e-3", noise_std=1e-3),
    Measurement("enc-12", bits=12),
    Measurement("enc-16", bits=16),
    Measurement("enc-20", bits=20),
]}
# Sensors of the held-out grid (bench/reports/realdata/held_out.py) that the defaults were not
# tuned on: other encoder resolutions, and an encoder whose counts jitter (noise before
# the quantizer, as an interpolating encoder's or a noisy analog sensor's ADC).
HELD_OUT_MEASUREMENTS: dict[str, Measurement] = {m.name: m for m in [
    Measurement("enc-14", bits=14),
    Measurement("enc-18", bits=18),
    Measurement("enc-16+noise-1e-4", noise_std=1e-4, bits=16),
]}


def measurement(name: str) -> Measurement:
    """A measurement of either grid by name."""
    return MEASUREMENTS.get(name) or HELD_OUT_MEASUREMENTS[name]


def seed_of(*keys: str) -> int:
    """A seed fixed by the condition's names (crc32: stable across runs and processes,
    unlike hash())."""
    return zlib.crc32("|".join(keys).encode())


def measure(x1: np.ndarray, m: Measurement, seed: int) -> np.ndarray:
    """The measured angle: true angle plus noise, or quantized by the encoder."""
    y = np.asarray(x1, dtype=float)
    if m.noise_std > 0:
        y = y + np.random.default_rng(seed).normal(0.0, m.noise_std, y.shape)
    if m.bits:
        y = m.quantum * np.round(y / m.quantum)
    return y


@dataclass(frozen=True)
class ModelError:
    """How the nominal model (b, c_nominal) differs from the truth."""

    name: str
    label: str
    inertia_factor: float = 1.0  # nominal J = factor x true J
    friction_factor: float = 1.0  # nominal c2, c3 = factor x true


MODEL_ERRORS: dict[str, ModelError] = {e.name: e for e in [
    ModelError("b-exact", "exact b, paper's c"),
    ModelError("J+10%", "J +10 %", inertia_factor=1.1),
    ModelError("J-10%", "J -10 %", inertia_factor=0.9),
    ModelError("friction+50%", "c2, c3 x1.5", friction_factor=1.5),
]}
# The held-out grid's nominal model: what a user starts from, the inertia 10 % off and
# the friction guessed at half its size.
HELD_OUT_MODEL = ModelError("J+10%,friction/2", "J +10 %, c2, c3 x0.5", inertia_factor=1.1,
                            friction_factor=0.5)


def model_error(name: str) -> ModelError:
    """A model error of either grid by name."""
    return MODEL_ERRORS.get(name) or {HELD_OUT_MODEL.name: HELD_OUT_MODEL}[name]

# The paper's 6.2 nominal coefficients (the plain case of data set A).
PAPER_NOMINAL_C = (2.0, 0.1, 0.1)


def nominal(error: ModelError, b_true: float, c_true: tuple[float, ...]
            ) -> tuple[float, tuple[float, float, float]]:
    """(b, (c1, c2, c3)) given to the methods that take a nominal model.

    "b-exact" is the paper's 6.2 setting: exact b, c = (2, 0.1, 0.1) to be
    identified.  A wrong inertia J' = f J scales every coefficient (all are
    divided by J): b' = b / f, c' = c / f.  The friction error multiplies c2, c3.
    """
    if error.name == "b-exact":
        return b_true, PAPER_NOMINAL_C
    f = error.inertia_factor
    c1, c2, c3 = (c / f for c in c_true[:3])
    return b_true / f, (c1, c2 * error.friction_factor, c3 * error.friction_factor)
