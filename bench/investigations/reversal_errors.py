"""Where the default FMU's velocity error is on one benchmark condition: within a few
samples of the velocity reversals or away from them (docs/design/observer.md, "Exact data:
reversals, the perturbation's trend, the position terms").

    .venv/bin/python -m bench.investigations.reversal_errors A,accurate,1000,clean,b-exact

The data set is made as bench/reports/real_measurements.py makes it (into --data, reused).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from bench.reports import real_measurements as rm
from bench.reports.realdata import methods, plants, sensors

REPO = Path(__file__).resolve().parents[2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("condition", help="data set,plant,rate,measurement,model error "
                        "(open-loop data set A only), e.g. A,accurate,1000,clean,b-exact")
    parser.add_argument("--data", type=Path, default=REPO / "build" / "real_measurements" / "data")
    parser.add_argument("--fmus", type=Path, default=REPO / "build" / "fmus")
    parser.add_argument("--after", type=int, default=5, help="samples after a reversal counted "
                        "as near it (and one before)")
    args = parser.parse_args()
    name, kind, rate, meas_name, model = args.condition.split(",")
    if name != "A":
        parser.error("only the open-loop data set A")
    path = rm.data_path(args.data, name, kind, int(rate))
    if not path.exists():
        args.data.mkdir(parents=True, exist_ok=True)
        rm.make_data(name, kind, (int(rate),), args.fmus, args.data)
    data = plants.Dataset.load(path)
    meas = sensors.MEASUREMENTS[meas_name]
    y = sensors.measure(data.x1, meas, sensors.seed_of(name, meas_name))
    b_nom, c_nom = sensors.nominal(sensors.MODEL_ERRORS[model], data.b, data.c)
    case = methods.Case(data, y, meas, b_nom, c_nom, 1.0)
    est = methods.run_fmu(case, "fmu-default", args.fmus / "SuperTwistingObserver.fmu")
    error = est.velocity - data.x2
    after = data.t > 1.0
    reversal = np.r_[False, np.diff(np.sign(data.x2)) != 0]
    near = np.zeros_like(reversal)
    for shift in range(-1, args.after + 1):
        near |= np.roll(reversal, shift)

    def rms(mask: np.ndarray) -> float:
        return float(np.sqrt(np.mean(error[mask] ** 2)))

    print(f"{args.condition}: {int(np.sum(reversal & after))} reversals after 1 s")
    print(f"velocity RMS error: all {rms(after):.3g}, away from reversals "
          f"{rms(after & ~near):.3g}, within -1..+{args.after} samples {rms(after & near):.3g}")
    print(f"largest error near a reversal {np.max(np.abs(error[after & near])):.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
