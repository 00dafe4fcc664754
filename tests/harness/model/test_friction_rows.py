"""The equations kept where Coulomb friction holds (harness.model.friction_rows)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bench.cases.two_link import NAMES, model_toml
from harness.model.friction_rows import away_from_reversals, friction_rows
from harness.model.log import ModelLog
from harness.model.reader import parse_model
from harness.model.zero_phase import ZeroPhase, regression


def test_friction_rows_leave_out_reversals_and_slow_stretches():
    h = 1e-3
    t = np.arange(0.0, 2.0, h)
    # joint 1 reverses at t = 0.5; joint 2 slows to 0.01 rad/s at t = 1.5 without reversing
    velocity = np.column_stack([t - 0.5, 0.01 + (t - 1.5) ** 2])
    rows = friction_rows(velocity, h, margin=0.05, min_speed=0.05)
    assert not rows[int(0.53 / h), 0] and rows[int(0.6 / h), 0]        # reversal margin 0.05 s
    assert not rows[int(1.5 / h), 1] and not rows[int(1.69 / h), 1]    # |q'| < 0.05
    assert rows[int(1.71 / h), 1] and rows[int(0.5 / h), 1]
    assert np.array_equal(friction_rows(velocity, h, 0.05, 0.0),
                          away_from_reversals(velocity, h, 0.05))
    with pytest.raises(ValueError, match="min_speed"):
        friction_rows(velocity, h, 0.05, -1.0)


def test_slow_margin_leaves_out_the_rows_after_a_slow_stretch():
    """A filtered row carries the friction of the filter's memory: with slow_margin a
    joint's rows within that time of a sample slower than min_speed are left out."""
    h = 1e-3
    speed = np.full((400, 1), 0.5)
    speed[100:110] = 0.01  # slow, without reversing
    plain = friction_rows(speed, h, margin=0.05, min_speed=0.05)
    assert plain[:100].all() and not plain[100:110].any() and plain[110:].all()
    rows = friction_rows(speed, h, margin=0.05, min_speed=0.05, slow_margin=0.08)
    assert rows[:20].all() and not rows[20:190].any() and rows[190:].all()


def _near_whole(events: np.ndarray, h: float, margin: float) -> np.ndarray:
    """(N, n) True within +-margin s of an event, by counting (the whole-log rule)."""
    half = int(round(margin / h))
    counts = np.cumsum(np.vstack([np.zeros((1, events.shape[1])), events]), axis=0)
    index = np.arange(len(events))
    return (counts[np.minimum(index + half + 1, len(events))]
            - counts[np.maximum(index - half, 0)]) > 0


def test_friction_rows_at_the_used_samples_are_the_whole_logs():
    h = 1e-3
    rng = np.random.default_rng(5)
    t = np.arange(5000) * h
    velocity = np.column_stack([np.sin(3.0 * t), 0.04 + 0.1 * np.sin(1.1 * t)])
    velocity[rng.integers(0, 5000, 20), 0] = 0.0  # isolated slow samples
    flips = np.zeros(velocity.shape, dtype=bool)
    flips[1:] = np.signbit(velocity[1:]) != np.signbit(velocity[:-1])
    whole = ~_near_whole(flips, h, 0.05) & ~_near_whole(np.abs(velocity) < 0.05, h, 0.02)
    assert np.array_equal(friction_rows(velocity, h, 0.05, 0.05, 0.02), whole)
    used = np.arange(3, 4990, 7)
    assert np.array_equal(friction_rows(velocity, h, 0.05, 0.05, 0.02, at=used), whole[used])
    assert 0.2 < whole.mean() < 0.9  # both kinds of rows


# a mass on a spring with viscous and Coulomb friction, beside a second coordinate without
TWO_MASSES = """
[model]
coordinates = ["x", "y"]
inputs = ["F", "G"]
equations = ["m*der(x,2) + k*x + fv*der(x) + fc*sign(der(x)) = F",
             "n*der(y,2) + c*y = G"]
[parameters]
m = { nominal = 1.0 }
k = { nominal = 100.0 }
fv = { nominal = 0.5 }
fc = { nominal = 0.2 }
n = { nominal = 2.0 }
c = { nominal = 50.0 }
"""


def test_a_model_knows_which_coordinates_enter_each_equation_inside_sign():
    model = parse_model(TWO_MASSES)
    assert model.coulomb_coordinates == ((0,), ())
    assert parse_model(model_toml(np.ones(len(NAMES)))).coulomb_coordinates == ((0,), (1,))


@pytest.mark.parametrize("decimation", [1, 10])
def test_the_friction_rows_leave_out_the_reversals_of_the_coordinate_in_sign(decimation):
    """x reverses every half second: its equation loses the rows within half a period of
    the cut-off of each reversal, y's keeps them all; the rows kept still hold exactly
    (zeroed before the decimation's filter)."""
    model = parse_model(TWO_MASSES)
    h = 1e-3
    t = np.arange(0.0, 4.0, h)
    x, y = 0.1 * np.sin(2 * np.pi * t), 0.05 * np.cos(3 * t)
    xd, xdd = 0.2 * np.pi * np.cos(2 * np.pi * t), -0.4 * np.pi ** 2 * np.sin(2 * np.pi * t)
    F = 1.0 * xdd + 100.0 * x + 0.5 * xd + 0.2 * np.sign(xd)
    G = 2.0 * (-0.45 * np.cos(3 * t)) + 50.0 * y
    log = ModelLog("test", t, np.column_stack([x, y]), np.column_stack([F, G]))
    settings = ZeroPhase.for_step(h, 20.0, decimation, "spectral", friction_rows=True)
    rows = regression(model, log, settings)
    assert rows.mask is not None and rows.mask.shape == rows.r.shape
    assert rows.mask[:, 1].all()
    middle = (rows.t > 0.5) & (rows.t < 3.5)
    # the reversals of x every 0.5 s, each margin 1.5 / 20 Hz = 0.075 s wide on either
    # side (|x'| below 5 % of its RMS is only +-0.011 s around each reversal)
    assert rows.mask[middle, 0].mean() == pytest.approx(1.0 - 2 * 0.075 / 0.5, abs=0.01)
    assert np.all(rows.Y[~rows.mask[:, 0], 0] == 0.0) or decimation > 1
    reversal = np.abs(rows.t - 1.25).argmin()   # x' = 0 at t = 0.25 + 0.5 k
    assert not rows.mask[reversal, 0]
    truth = np.array([1.0, 100.0, 0.5, 0.2, 2.0, 50.0])
    error = rows.Y @ truth - rows.r
    inside = rows.mask[:, 0] & middle  # away from the log's ends
    assert np.abs(error[inside, 0]).max() < 0.02 * 0.2  # the Coulomb level
    plain = regression(model, log, dataclasses.replace(settings, friction_rows=False))
    assert plain.mask is None
    assert np.abs(plain.Y @ truth - plain.r)[:, 0].max() > 0.5 * 0.2
