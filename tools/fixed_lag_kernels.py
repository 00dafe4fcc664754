"""Writes fmu/src/core/fixed_lag_kernels.h: the fixed-lag window's velocity and
acceleration kernels (fmu/src/core/fixed_lag.h), designed here once, since their design
needs a dense least-squares solve of up to 241 unknowns that the FMU would otherwise
run at every instantiation.

    python -m tools.fixed_lag_kernels [--check]

The smoothing kernel k0 is the Blackman-windowed sinc K of cut-off a (radians per
sample) sampled at the integers, normalized to sum 1, as fixed_lag.c computes it. Its
response H0(w) = sum_j k0_j e^{-i w j}. The smoothed equation holds when the velocity
and acceleration kernels respond i w H0(w) and -w^2 H0(w): then a signal's smoothed
derivative is the derivative's smoothed samples. Sampling K' and K'' does not give
that: their aliases, small, vary on the window's scale near w = 0, and normalizing
K'' on a parabola (its second moment, the response's curvature at 0) scaled it by
1 + 6.8e-3 across the band at a = 0.2 of the sample rate. Here each kernel of the
same length is the least squares fit of its response to i w H0 or -w^2 H0 on a fine
grid, with weight 1 on the band 0 .. a + 3 pi / T (T = half + 1: the Blackman main
lobe's half-width, past which H0 is below 1e-4) and STOP outside it (there H0 is
about 0 and the fit keeps the noise gain of K'' sampled), subject to exact constants,
ramps and parabolas.  --check only compares with the header in the tree: the same
definitions, and kernel values within CHECK_TOLERANCE of the largest (the solve's last
bits follow the machine's BLAS), the comment's error figures aside.
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
HEADER = ROOT / "fmu" / "src" / "core" / "fixed_lag_kernels.h"
TUNING = ROOT / "fmu" / "src" / "core" / "tuning.h"
STOP = 1e-3            # the fit's weight (on the response) outside the band


def tuning(name: str) -> float:
    match = re.search(rf"^#define {name} ([0-9.eE+-]+)", TUNING.read_text(), re.MULTILINE)
    if match is None:
        raise RuntimeError(f"{TUNING} does not define {name}")
    return float(match.group(1))


def smoothing(fraction: float, half: int) -> np.ndarray:
    """k0[j], j = 0 .. half: K at j, normalized to sum 1 over -half .. half."""
    a, T = 2 * np.pi * fraction, half + 1.0
    t = np.arange(half + 1, dtype=float)
    s = np.empty_like(t)
    s[0] = a / np.pi
    s[1:] = np.sin(a * t[1:]) / (np.pi * t[1:])
    b = np.pi / T
    k0 = s * (0.42 + 0.5 * np.cos(b * t) + 0.08 * np.cos(2 * b * t))
    return k0 / (k0[0] + 2 * k0[1:].sum())


def constrained_fit(A: np.ndarray, target: np.ndarray, C: np.ndarray, d: np.ndarray
                    ) -> np.ndarray:
    """argmin |A x - target| subject to C x = d (through C's null space)."""
    x0 = np.linalg.lstsq(C, d, rcond=None)[0]
    _, _, vt = np.linalg.svd(C)
    null = vt[C.shape[0]:].T
    y = np.linalg.lstsq(A @ null, target - A @ x0, rcond=None)[0]
    return x0 + null @ y


def derivatives(fraction: float, half: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """k0, k1, k2 (units of h^-derivative; k1[j] weighs y_{c+j} - y_{c-j}, k2 and k0
    y_{c+j} + y_{c-j} for j > 0)."""
    k0 = smoothing(fraction, half)
    j = np.arange(half + 1, dtype=float)
    w = np.linspace(0.0, np.pi, max(8001, 32 * (half + 1)))
    band = 2 * np.pi * fraction + 3 * np.pi / (half + 1)
    weight = np.where(w <= band, 1.0, STOP)[:, None]
    cosines = 2 * np.cos(np.outer(w, j))
    cosines[:, 0] = 1.0
    H0 = cosines @ k0
    twice = np.where(j > 0, 2.0, 1.0)
    k2 = constrained_fit(weight * cosines, weight[:, 0] * -w ** 2 * H0,
                         np.vstack([twice, twice * j ** 2]), np.array([0.0, 2.0]))
    sines = 2 * np.sin(np.outer(w, j[1:]))
    k1 = np.concatenate([[0.0], constrained_fit(weight * sines, weight[:, 0] * w * H0,
                                                (2 * j[1:])[None, :], np.array([1.0]))])
    return k0, k1, k2


def candidates() -> list[tuple[float, int]]:
    fraction, cycles = tuning("FL_HIGHEST_FRACTION"), tuning("FL_CYCLES")
    out = []
    for _ in range(int(tuning("FL_CANDIDATES"))):
        out.append((fraction, int(np.ceil(cycles / fraction - 1e-9))))
        fraction *= 0.5
    return out


def text() -> str:
    rows, offsets, report = [], [], []
    offset = 0
    for fraction, half in candidates():
        k0, k1, k2 = derivatives(fraction, half)
        offsets.append(offset)
        offset += half + 1
        rows.append((k1, k2))
        w = np.linspace(1e-3, 0.9 * 2 * np.pi * fraction, 400)
        cos = 2 * np.cos(np.outer(w, np.arange(half + 1)))
        cos[:, 0] = 1.0
        sin = 2 * np.sin(np.outer(w, np.arange(half + 1)))
        H0 = cos @ k0
        e1 = np.max(np.abs(sin @ k1 / (w * H0) - 1))
        e2 = np.max(np.abs(cos @ k2 / (-w ** 2 * H0) - 1))
        report.append(f" * cut-off {fraction:g}, half {half}: velocity {e1:.1e}, "
                      f"acceleration {e2:.1e}")
    lines = [
        "/* Generated by `python -m tools.fixed_lag_kernels` from tuning.h: do not edit.",
        " * The fixed-lag window's velocity and acceleration kernels (fixed_lag.h), per",
        " * candidate, for a step of 1: k1 then k2 at j = 0 .. half of each candidate,",
        " * from FL_KERNEL_OFFSET[c].  Their responses' largest relative error against",
        " * i w H0 and -w^2 H0 over 0.001 .. 0.9 of the cut-off (radians per sample):",
        *report,
        " */",
        "#ifndef FIXED_LAG_KERNELS_H",
        "#define FIXED_LAG_KERNELS_H",
        "",
        f"#define FL_KERNEL_HIGHEST_FRACTION {tuning('FL_HIGHEST_FRACTION')!r}",
        f"#define FL_KERNEL_CANDIDATES {int(tuning('FL_CANDIDATES'))}",
        f"#define FL_KERNEL_CYCLES {tuning('FL_CYCLES')!r}",
        f"#define FL_KERNEL_SIZE {offset}",
        "",
        "static const int FL_KERNEL_OFFSET[FL_KERNEL_CANDIDATES] = {"
        + ", ".join(str(o) for o in offsets) + "};",
    ]
    for name, index in (("FL_KERNEL_VELOCITY", 0), ("FL_KERNEL_ACCELERATION", 1)):
        values = [f"{v:.17g}" for k in rows for v in k[index]]
        lines.append(f"static const double {name}[FL_KERNEL_SIZE] = {{")
        for start in range(0, len(values), 4):
            lines.append("    " + ", ".join(values[start:start + 4]) + ",")
        lines.append("};")
    lines += ["", "#endif", ""]
    return "\n".join(lines)


#: --check: a kernel value may differ from the tree's by this much of the largest value
CHECK_TOLERANCE = 1e-9
_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def same_table(old: str, new: str) -> bool:
    """The two headers' code (comments aside) is the same but for the real numbers, which
    agree within CHECK_TOLERANCE of the largest (integers: sizes, offsets, exactly)."""
    def code(text: str) -> tuple[str, np.ndarray]:
        body = text[text.index("*/") + 2:] if "*/" in text else text
        reals = [x for x in _NUMBER.findall(body) if not x.lstrip("+-").isdigit()]
        return (_NUMBER.sub(lambda m: m.group() if m.group().lstrip("+-").isdigit() else "#",
                            body), np.array([float(x) for x in reals]))
    (shape_old, numbers_old), (shape_new, numbers_new) = code(old), code(new)
    if shape_old != shape_new or numbers_old.shape != numbers_new.shape:
        return False
    scale = float(np.abs(numbers_new).max(initial=0.0))
    return bool(np.all(np.abs(numbers_old - numbers_new) <= CHECK_TOLERANCE * scale))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="compare with the header in the tree instead of writing it")
    args = parser.parse_args()
    new = text()
    if args.check:
        same = HEADER.exists() and same_table(HEADER.read_text(), new)
        print(f"{HEADER}: {'up to date' if same else 'differs: run python -m tools.fixed_lag_kernels'}")
        return 0 if same else 1
    HEADER.write_text(new)
    print(f"wrote {HEADER}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
