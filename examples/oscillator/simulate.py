"""Two logs of a cubic oscillator for the example (not measured data: a simulation).

    python examples/oscillator/simulate.py --out DIR

writes DIR/oscillator.csv (estimation, 20,000 samples) and DIR/oscillator_validation.csv
(another multisine), columns t [s], y, u at 610 Hz: the oscillator of oscillator.toml
resonating at 68 Hz (a ninth of the sample rate), damping ratio 0.03, driven by a
broadband multisine (0.5-150 Hz), 0.5 % noise on y. The simulation is the benchmark's
case (bench/cases/oscillator.py), integrated at 8 Runge-Kutta sub-steps per sample on the
exact input.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the checkout's bench/

from bench.cases import oscillator  # noqa: E402

TRUTH = oscillator.TRUTH
SAMPLES = 20_000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for name, seed in (("oscillator", 1), ("oscillator_validation", 2)):
        oscillator.write(oscillator.make_log(seed, SAMPLES), args.out / f"{name}.csv")
    print(f"wrote {args.out / 'oscillator.csv'} and {args.out / 'oscillator_validation.csv'}")


if __name__ == "__main__":
    main()
