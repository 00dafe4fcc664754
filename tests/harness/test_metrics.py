"""harness.metrics: the closed loops' figures (convergence time, delay, masks)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.metrics import away_from_jumps, best_shift, convergence_time


def test_convergence_is_the_first_time_after_which_the_error_stays_small():
    t = np.arange(6) * 0.1
    assert convergence_time(t, np.array([1, 0.5, 0.01, 0.2, 0.001, 0.0]), 0.1) == \
        pytest.approx(0.4)
    assert convergence_time(t, np.zeros(6), 0.1) == 0.0
    assert math.isinf(convergence_time(t, np.array([0, 0, 0, 0, 0, 1.0]), 0.1))


def test_the_delay_of_a_shifted_signal_is_found():
    t = np.arange(0.0, 2.0, 1e-3)
    truth = np.sin(2 * np.pi * t)
    estimate = np.sin(2 * np.pi * (t - 0.025))  # 25 ms late
    shift, rms = best_shift(t, estimate, truth, np.ones_like(t, dtype=bool), 0.1)
    assert shift == pytest.approx(0.025, abs=1e-9) and rms < 1e-9


def test_the_mask_leaves_out_the_time_around_each_jump():
    t = np.arange(10) * 1.0
    signal = np.where(t < 5, 0.0, 1.0)
    mask = away_from_jumps(t, signal, before=1.0, after=2.0)
    assert mask.tolist() == [True] * 4 + [False] * 4 + [True] * 2
