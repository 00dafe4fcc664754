"""Cost per macro step of the 3-FMU closed loop: native vs plain-Python master loop.

    .venv/bin/python -m bench.perf.master_loop [--repeats 5]

Runs scenario 6.2 with the FMU's default (improved) method (observer + pendulum
+ twisting controller, H = 1e-4 s) for
a fixed number of macro steps on each loop and prints the median wall time
per macro step over the repeats and the ratio.  It also times the native loop
with the links removed (only the three fmi2DoStep calls): the difference is
the coupling cost of the loop itself; the rest is the models' own work (the
plant's doStep runs 10 RK4 steps per macro step).  Results vary with the
machine's load: quote the medians and the ratio.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from harness.master import initialize, run
from harness.scenarios import COMMUNICATION_STEP, PROBES, SCENARIOS, build, improved_overrides

REPO = Path(__file__).resolve().parents[2]

def time_loop(use_native: bool, steps: int, coupled: bool = True) -> float:
    s = SCENARIOS["6.2"]
    sim = build(s, REPO / "build" / "fmus")
    try:
        noise = np.zeros(steps)
        initialize(sim, 0.0, {"plant": s.plant, "controller": s.controller,
                              "observer": {**s.observer, **improved_overrides(s)}},
                   {"noise": noise})
        if not coupled:  # initialized with the links, run without them
            sim.links = []
        start = time.perf_counter()
        run(sim, 0.0, steps * COMMUNICATION_STEP, COMMUNICATION_STEP, PROBES[:1],
            decimation=steps, signals={"noise": noise}, use_native=use_native)
        return (time.perf_counter() - start) / steps
    finally:
        sim.close()


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--native-steps", type=int, default=200_000)
    parser.add_argument("--python-steps", type=int, default=20_000)
    args = parser.parse_args()
    native = [time_loop(True, args.native_steps) for _ in range(args.repeats)]
    python = [time_loop(False, args.python_steps) for _ in range(args.repeats)]
    bare = [time_loop(True, args.native_steps, coupled=False) for _ in range(args.repeats)]
    n, p, b = statistics.median(native), statistics.median(python), statistics.median(bare)
    print(f"native loop: median {n * 1e6:.3f} us per macro step "
          f"({args.native_steps} steps x {args.repeats})")
    print(f"python loop: median {p * 1e6:.3f} us per macro step "
          f"({args.python_steps} steps x {args.repeats})")
    print(f"native, doStep calls only: median {b * 1e6:.3f} us per macro step; "
          f"coupling cost of the native loop: {(n - b) * 1e6:.3f} us")
    print(f"ratio python/native: {p / n:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
