"""The refinement's held-out check (harness/model/refine.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.model.refine import RefinementCheck


def check(least_squares: list[float], refined: list[float]) -> RefinementCheck:
    return RefinementCheck(np.array(least_squares), np.array(refined), np.zeros((2, 3)))


def test_each_half_counts_by_its_relative_change():
    """The coarse two-link arm's figures: a lower mean error (22.5 % against 22.9 %) made of
    one half won by 2.5 times and the other lost by 4.2 times is no improvement; EMPS's
    (both halves a little better) is one."""
    two_link = check([0.0689, 0.3895], [0.2917, 0.1580])
    assert two_link.refined < two_link.least_squares and not two_link.improves
    assert two_link.ratio == pytest.approx(math.sqrt(0.2917 / 0.0689 * 0.1580 / 0.3895))
    assert check([0.004913, 0.004618], [0.004798, 0.004558]).improves
    assert check([0.02, 0.02], [0.01, 0.03]).improves   # 0.5 and 1.5: sqrt(0.75) < 1
    assert not check([0.02, 0.02], [0.02, 0.02]).improves   # a tie is no win


def test_undefined_or_diverged_runs_are_no_win():
    assert not check([0.0, 0.01], [0.0, 0.005]).improves
    assert not check([0.01, 0.01], [0.005, math.inf]).improves
    assert check([0.01, math.inf], [0.005, 0.02]).improves


def test_the_check_reports_each_half():
    record = check([0.02, 0.03], [0.01, 0.005]).as_dict()
    assert record["least_squares"] == 0.025 and record["refined"] == 0.0075
    assert record["ratio"] == pytest.approx(math.sqrt(0.5 / 6))
    assert record["per_half"] == {"least_squares": [0.02, 0.03], "refined": [0.01, 0.005]}


def test_the_halves_spread_is_half_their_difference():
    halves = np.array([[1.0, 2.0, 3.0], [1.2, 2.0, 2.0]])
    spread = RefinementCheck(np.array([0.1, 0.1]), np.array([0.05, 0.05]), halves).spread()
    assert spread == pytest.approx([0.1, 0.0, 0.5])
