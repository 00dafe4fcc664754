"""Two logs of the two-mass system for the example (not measured data: a simulation).

    python examples/two_mass/simulate.py --out DIR

writes DIR/two_mass.csv (estimation) and DIR/two_mass_validation.csv (another input),
columns time [s], x1, x2 [m], F [N], 20 s at 1 kHz: the system of two_mass.toml with
"true" values away from the file's nominal ones (TRUTH), pushed by a sum of sines, both
positions read by encoders of 1 um.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

TRUTH = {"m1": 2.4, "m2": 0.8, "c1": 0.8, "c2": 0.3, "k": 350.0, "d": 1.5}
RATE, SECONDS, ENCODER = 1000.0, 20.0, 1e-6


def force(t: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    frequencies = rng.uniform(0.3, 8.0, 6)
    phases = rng.uniform(0, 2 * np.pi, 6)
    return 15.0 * np.sum(np.sin(2 * np.pi * np.outer(t, frequencies) + phases), axis=1)


def simulate(seed: int) -> dict[str, np.ndarray]:
    p = TRUTH
    t = np.arange(0.0, SECONDS, 1.0 / RATE)

    def rhs(time, state):
        x1, x2, v1, v2 = state
        spring = p["k"] * (x1 - x2) + p["d"] * (v1 - v2)
        F = force(np.array([time]), seed)[0]
        return [v1, v2, (F - p["c1"] * v1 - spring) / p["m1"], (spring - p["c2"] * v2) / p["m2"]]

    solution = solve_ivp(rhs, (0.0, SECONDS), [0.0, 0.0, 0.0, 0.0], t_eval=t, method="DOP853",
                         rtol=1e-10, atol=1e-12)
    x1, x2 = (ENCODER * np.round(x / ENCODER) for x in solution.y[:2])
    return {"time": t, "x1": x1, "x2": x2, "F": force(t, seed)}


def write(path: Path, columns: dict[str, np.ndarray]) -> None:
    pd.DataFrame(columns).to_csv(path, index=False, float_format="%.17g")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    write(args.out / "two_mass.csv", simulate(seed=1))
    write(args.out / "two_mass_validation.csv", simulate(seed=2))
    print(f"wrote {args.out / 'two_mass.csv'} and {args.out / 'two_mass_validation.csv'}")


if __name__ == "__main__":
    main()
