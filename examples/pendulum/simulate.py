"""Two logs of the paper's pendulum for the example (not measured data: a simulation).

    python examples/pendulum/simulate.py --out DIR

writes DIR/pendulum.csv (estimation) and DIR/pendulum_validation.csv (another input),
columns t [s], theta [rad], u [N.m], 20 s at 1 kHz: the pendulum of pendulum.toml with
"true" values away from the file's nominal ones (TRUTH), driven by a sum of sines, its
angle read by a 12-bit encoder (2 pi / 4096 rad steps).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

TRUTH = {"J": 0.95, "ML": 1.05, "Vs": 0.25, "Ps": 0.35}
G = 9.815
RATE, SECONDS, ENCODER = 1000.0, 20.0, 2 * np.pi / 4096


def torque(t: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    frequencies = rng.uniform(0.2, 2.5, 6)
    phases = rng.uniform(0, 2 * np.pi, 6)
    return 1.2 * np.sum(np.sin(2 * np.pi * np.outer(t, frequencies) + phases), axis=1)


def simulate(seed: int) -> dict[str, np.ndarray]:
    p = TRUTH
    t = np.arange(0.0, SECONDS, 1.0 / RATE)

    def rhs(time, state):
        theta, omega = state
        u = torque(np.array([time]), seed)[0]
        friction = p["Vs"] * omega + p["Ps"] * np.tanh(omega / 1e-3)  # sign(omega), smoothed
        return [omega, (u - p["ML"] * G / 2 * np.sin(theta) - friction) / p["J"]]

    solution = solve_ivp(rhs, (0.0, SECONDS), [0.0, 0.0], t_eval=t, max_step=1e-3,
                         rtol=1e-9, atol=1e-11)
    theta = ENCODER * np.round(solution.y[0] / ENCODER)
    return {"t": t, "theta": theta, "u": torque(t, seed)}


def write(path: Path, columns: dict[str, np.ndarray]) -> None:
    pd.DataFrame(columns).to_csv(path, index=False, float_format="%.17g")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    write(args.out / "pendulum.csv", simulate(seed=1))
    write(args.out / "pendulum_validation.csv", simulate(seed=2))
    print(f"wrote {args.out / 'pendulum.csv'} and {args.out / 'pendulum_validation.csv'}")


if __name__ == "__main__":
    main()
