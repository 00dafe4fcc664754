"""Soak run: a very long closed loop with identification on, in chunks through
the harness's native loop, checking that nothing drifts or leaks.

    .venv/bin/python -m tools.abuse.soak               1e4 s of scenario 6.2 (1e8 steps)
    .venv/bin/python -m tools.abuse.soak --seconds 200      a short one

Default: scenario 6.2 (LSM identification, the paper's method) for 1e4 s of
model time at H = h = 1e-4 s, i.e. 1e8 macro steps, 1e8 internal steps of the
observer and 1e9 of the plant.  After every chunk it checks:

* every probe finite over the whole chunk (no NaN, no Inf);
* gamma_trace within (0, m / rho] (the LSM's trace(Gamma) only decreases
  from Gamma(0) = I / rho);
* the observer still tracks the plant (|x1_hat - theta| small);
* RSS flat: after the first WARMUP_CHUNKS chunks it may grow by at most
  --rss-slack MB in total.

Exit status 0 if every check held; a JSON summary goes to --out if given.
Not part of CI (minutes of wall time); see the report for a run's figures.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from harness.master import initialize, run
from harness.scenarios import COMMUNICATION_STEP, PROBES, SCENARIOS, build
from harness.values import BadValue, argparse_type, real

REPO = Path(__file__).resolve().parents[2]

# The first chunks settle the allocator (glibc raises its mmap threshold after the
# first large temporary array is freed, and keeps later ones on the heap).
WARMUP_CHUNKS = 3


def rss_mb() -> float:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def _chunk(text: str) -> float:
    """--chunk: a whole number (>= 1) of communication steps H."""
    chunk = real("--chunk", text, 0.0, low_open=True)
    steps = chunk / COMMUNICATION_STEP
    if steps < 1 or abs(steps - round(steps)) > 1e-6 * steps:
        raise BadValue(f"--chunk {text}: give a whole number of communication steps of "
                       f"{COMMUNICATION_STEP:g} s (at least one)")
    return chunk


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scenario", default="6.2", choices=list(SCENARIOS))
    p.add_argument("--seconds", type=argparse_type(real, "--seconds", low=0.0, low_open=True),
                   default=1e4, help="model time, > 0 (default 1e4 s)")
    p.add_argument("--chunk", type=argparse_type(lambda _name, text: _chunk(text), "--chunk"),
                   default=100.0, help="model time per chunk [s], a multiple of H = 1e-4 s")
    p.add_argument("--noise", type=argparse_type(real, "--noise", low=0.0), default=0.0,
                   help="measurement noise std [rad], >= 0")
    p.add_argument("--rss-slack", type=argparse_type(real, "--rss-slack", low=0.0), default=8.0,
                   help="allowed RSS growth [MB], >= 0")
    p.add_argument("--fmu-dir", default=os.environ.get("STO_FMU_DIR", str(REPO / "build" / "fmus")))
    p.add_argument("--out", help="write a JSON summary here")
    args = p.parse_args(argv)

    s = SCENARIOS[args.scenario]
    H = COMMUNICATION_STEP
    steps_per_chunk = int(round(args.chunk / H))
    n_chunks = max(1, int(math.ceil(args.seconds / args.chunk - 1e-9)))  # never nothing
    m = sum(1 for k in range(1, 9) if s.observer.get(f"identify[{k}]", k <= 3))
    rho = float(s.observer.get("rho", 1e-3))
    gamma_bound = m / rho * (1 + 1e-9)
    rng = np.random.default_rng(0)

    sim = build(s, Path(args.fmu_dir))
    problems: list[str] = []
    rows = []
    wall0 = time.monotonic()
    try:
        noise = np.zeros(steps_per_chunk) if args.noise == 0 else rng.normal(0, args.noise,
                                                                             steps_per_chunk)
        initialize(sim, 0.0, {"plant": s.plant, "controller": s.controller,
                              "observer": s.observer}, {"noise": noise})
        rss_start = rss_mb()
        rss_after_warmup = None
        t = 0.0
        for chunk in range(n_chunks):
            t0 = chunk * args.chunk
            if args.noise > 0:
                noise = rng.normal(0.0, args.noise, steps_per_chunk)
            records = run(sim, t0, t0 + args.chunk, H, PROBES,
                          decimation=max(1, steps_per_chunk // 100),
                          signals={"noise": noise}, use_native=True)
            t = t0 + args.chunk
            values = {name: records[name] for name in PROBES}
            for name, v in values.items():
                if not np.all(np.isfinite(v)):
                    problems.append(f"chunk {chunk}: {name} not finite")
            gamma = values["observer.gamma_trace"]
            if not (np.all(gamma > 0) and np.all(gamma <= gamma_bound)):
                problems.append(f"chunk {chunk}: gamma_trace outside (0, {gamma_bound}]: "
                                f"[{gamma.min()}, {gamma.max()}]")
            tracking = float(np.max(np.abs(values["observer.x1_hat[1]"] - values["plant.theta"])))
            if not tracking < 1e-2:
                problems.append(f"chunk {chunk}: |x1_hat - theta| up to {tracking}")
            rss = rss_mb()
            if chunk == min(WARMUP_CHUNKS, n_chunks) - 1:
                rss_after_warmup = rss
            row = {"t": t, "wall": time.monotonic() - wall0, "rss_mb": rss,
                   "gamma_trace": float(gamma[-1]), "tracking": tracking,
                   "theta_hat": [float(values[f"observer.theta_hat[1,{k}]"][-1]) for k in (1, 2, 3)]}
            rows.append(row)
            print(f"t = {t:8.0f} s  wall {row['wall']:7.1f} s  RSS {rss:7.1f} MB  "
                  f"gamma_trace {row['gamma_trace']:.4g}  theta_hat "
                  f"{', '.join(f'{v:.5f}' for v in row['theta_hat'])}  "
                  f"|x1_hat - theta| <= {tracking:.2e}", flush=True)
            if problems:
                break
        growth = rss_mb() - rss_after_warmup if rss_after_warmup is not None else 0.0
        if growth > args.rss_slack:
            problems.append(f"RSS grew by {growth:.1f} MB after the warm-up chunks "
                            f"(slack {args.rss_slack} MB)")
    finally:
        sim.close()
    wall = time.monotonic() - wall0
    macro_steps = int(round(t / H))
    summary = {
        "scenario": args.scenario, "model_time_s": t, "macro_steps": macro_steps,
        "observer_internal_steps": macro_steps,
        "plant_internal_steps": macro_steps * int(round(H / float(s.plant.get("h", 1e-5)))),
        "wall_s": wall, "us_per_macro_step": 1e6 * wall / max(1, macro_steps),
        "rss_start_mb": rss_start, "rss_after_warmup_mb": rss_after_warmup,
        "rss_end_mb": rss_mb(), "c_true": s.c_true[:3],
        "theta_hat_end": rows[-1]["theta_hat"] if rows else None,
        "gamma_trace_end": rows[-1]["gamma_trace"] if rows else None,
        "problems": problems, "chunks": rows,
    }
    print(json.dumps({k: v for k, v in summary.items() if k != "chunks"}, indent=1))
    if args.out:
        Path(args.out).write_text(json.dumps(summary, indent=1))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
