"""A log's clock made even (harness.clock): taken as it is, resampled, or refused."""
from __future__ import annotations

import numpy as np
import pytest

from harness.clock import ClockError, even_steps


def _place(k: int) -> str:
    return f"row {k}"


def test_an_even_clock_is_taken_as_it_is():
    t = np.arange(100) * 0.01
    q, u = np.sin(t)[:, None], np.cos(t)[:, None]
    log = even_steps(t, q, u, 0.01, _place)
    assert log.resampled is None and log.t is t and log.q is q and log.u is u


def test_a_jittering_clock_is_resampled_onto_its_mean_step():
    """Steps of 10 ms +-30 %: positions by cubic splines (a smooth motion within 1e-6 of
    itself), the other columns linearly."""
    rng = np.random.default_rng(1)
    t = np.cumsum(0.01 * (1 + 0.3 * rng.uniform(-1, 1, 2000)))
    q, u = np.sin(2 * t)[:, None], (3 * t)[:, None]
    log = even_steps(t, q, u, 0.01, _place)
    assert log.resampled is not None and "the clock jitters" in log.resampled
    assert np.allclose(np.diff(log.t), (t[-1] - t[0]) / (len(t) - 1))
    assert np.max(np.abs(log.q[:, 0] - np.sin(2 * log.t))) < 1e-6
    assert np.allclose(log.u[:, 0], 3 * log.t)


@pytest.mark.parametrize("change, words", [
    (lambda t: np.concatenate([t[:50], t[53:]]), "row 50: a gap of 0.04 s"),
    (lambda t: np.concatenate([t[:50], t[49:]]), "row 50: t does not increase"),
])
def test_a_gap_or_a_step_back_is_refused_where_it_is(change, words):
    t = change(np.arange(100) * 0.01)
    with pytest.raises(ClockError, match=words):
        even_steps(t, np.zeros((len(t), 1)), np.zeros((len(t), 0)), 0.01, _place)
