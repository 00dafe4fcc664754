"""The EMPS closed-loop simulation's exact stepping (bench/reports/emps_closed_loop.py)
against a fine implicit Euler with a set-valued Coulomb term, whose error shrinks with
its step: sliding, a reversal through zero, sticking and breaking away."""
from __future__ import annotations

import pytest

from bench.reports.emps_closed_loop import advance

THETA = (95.0, 203.0, 20.4, -3.2)


def fine(q: float, v: float, force: float, duration: float, steps: int = 200_000):
    mass, viscous, coulomb, offset = THETA
    h = duration / steps
    for _ in range(steps):
        a = mass * v + h * (force - offset)  # M (v' - v) = h (F - OF - Fv v' - Fc s)
        if a > h * coulomb:
            v = (a - h * coulomb) / (mass + h * viscous)
        elif a < -h * coulomb:
            v = (a + h * coulomb) / (mass + h * viscous)
        else:
            v = 0.0
        q += h * v
    return q, v


@pytest.mark.parametrize("v, force", [
    (0.05, 40.0),     # sliding forward, the force drives it on
    (0.05, -60.0),    # braking: stops, then reverses
    (0.002, 0.0),     # stops and sticks (|F - OF| < Fc)
    (0.0, 10.0),      # stuck, the force stays within the Coulomb level
    (0.0, -40.0),     # breaks away backwards
])
def test_advance_equals_a_fine_integration(v, force):
    q, v_end = advance(0.1, v, force, 0.2, THETA)
    q_ref, v_ref = fine(0.1, v, force, 0.2)
    assert q == pytest.approx(q_ref, abs=2e-7)
    assert v_end == pytest.approx(v_ref, abs=2e-6)


def test_a_stuck_drive_stays_put():
    assert advance(0.1, 0.0, 10.0, 1.0, THETA) == (0.1, 0.0)
