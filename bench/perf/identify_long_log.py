"""identify on a long log: wall time and peak memory of ``sto-harness identify``.

    .venv/bin/python -m bench.perf.identify_long_log [--samples 10000000] [--csv-decimation N]
                                                [--format csv|parquet]

Writes a log of N samples at 1 kHz (a pendulum-like y, a two-tone u; about 55
bytes a row) into a temporary folder, then runs the command line on it in a
child process and reports the child's wall time, CPU time and peak resident memory
(its own rusage from wait4: ru_maxrss).  The log is written by another child,
and this process imports neither numpy nor pyarrow: Linux carries the peak
memory of the process that starts a program over into the program's
ru_maxrss, so a large parent would be counted.  The issue's target: 10^7
samples in <= 15 s and <= 300 MB.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def write_log(path: Path, samples: int, chunk: int = 1_000_000) -> None:
    import numpy as np
    import pyarrow as pa
    import pyarrow.csv as pacsv

    with pacsv.CSVWriter(str(path), pa.schema([("time", pa.float64()), ("theta", pa.float64()),
                                               ("tau", pa.float64())])) as writer:
        for start in range(0, samples, chunk):
            t = np.arange(start, min(samples, start + chunk)) * 1e-3
            writer.write_table(pa.table({"time": t, "theta": 0.2 * np.sin(1.3 * t)
                                         + 0.05 * np.sin(7.1 * t),
                                         "tau": np.sin(2.0 * t) + 0.5 * np.sin(5.3 * t)}))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--csv-decimation", type=int, default=1)
    parser.add_argument("--format", choices=["csv", "parquet"], default="csv")
    parser.add_argument("--write-log", type=Path, help=argparse.SUPPRESS)  # the writing child
    args = parser.parse_args()
    if args.write_log:
        write_log(args.write_log, args.samples)
        return 0
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "log.csv"
        start = time.perf_counter()
        subprocess.run([sys.executable, __file__, "--samples", str(args.samples),
                        "--write-log", str(log)], check=True)
        print(f"log: {args.samples} samples, {log.stat().st_size / 1e6:.0f} MB "
              f"(written in {time.perf_counter() - start:.1f} s)")
        command = [sys.executable, "-m", "harness", "identify", str(log), "--out",
                   str(Path(folder) / "out"), "--columns", "y=theta,u=tau", "--quiet",
                   "--csv-decimation", str(args.csv_decimation), "--format", args.format]
        start = time.perf_counter()
        errors = (Path(folder) / "stderr.txt").open("w+")
        child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=errors)
        _, status, usage = os.wait4(child.pid, 0)  # this child's own rusage
        wall = time.perf_counter() - start
        peak = usage.ru_maxrss / 1024  # kB -> MB
        returncode = os.waitstatus_to_exitcode(status)
        child.returncode = returncode  # reaped here: Popen must not wait for it
        if returncode not in (0, 1):
            errors.seek(0)
            print(errors.read(), file=sys.stderr)
            return 1
        table = Path(folder) / "out" / f"estimates.{args.format}"
        written = table.stat().st_size / 1e6
        print(f"identify: {wall:.1f} s wall, peak resident memory {peak:.0f} MB, "
              f"{table.name} {written:.0f} MB (every {args.csv_decimation}. row), "
              f"exit status {returncode}")
        # CPU time depends less on other jobs than the wall time on a shared machine
        print(f"CPU time {usage.ru_utime:.1f} s user, {usage.ru_stime:.1f} s system; "
              f"load average {os.getloadavg()[0]:.1f}")
        print(f"{args.samples / wall / 1e6:.2f} million samples per second")
    return 0


if __name__ == "__main__":
    sys.exit(main())
