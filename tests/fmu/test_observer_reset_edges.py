"""A rising edge of identifier_reset is never lost.

The observer used to read identifier_reset only in communication steps that
reach an internal grid point, so with H < h (or H not a multiple of h) a
reset held for one short step was lost.  Here a one-step pulse is given at
many times (on and off the internal grid) for communication steps shorter
than, equal to, longer than and not multiples of h, with both identifier
forms and both identifiers: right after the pulse, the identifier must have
restarted (the trace of its Gamma back near its initial I/rho), and it must
not restart without a pulse, nor on a falling edge or a level held high.
"""
from __future__ import annotations

import math

import pytest

from tools.abuse.abuse_fmi import MODELS, OK, Raw, isolated

OBS = MODELS[0]
RUN = 0.4  # s of identification before the pulse: trace(Gamma) falls far below I/rho


def _signals(t: float) -> dict:
    return {"y[1]": math.sin(3 * t) + 0.3 * math.sin(17 * t), "u": math.cos(5 * t)}


def _run(h: float, H: float, pulse_steps: set[int], parameters: dict, n: int) -> list[float]:
    """gamma_trace after each of n steps of H, identifier_reset high in pulse_steps."""
    f = Raw(OBS)
    assert f.initialize({"h": h, "identifier_start": 0, **parameters}) == OK, f.messages()
    traces = []
    for k in range(n):
        t = k * H
        assert f.set({**_signals(t), "identifier_reset": k in pulse_steps}) == OK
        assert f.do_step(t, H) == OK, f.messages()
        traces.append(f.get_real(["gamma_trace"])[1][0])
    f.free()
    return traces


def _pulse(h: float, H: float, offset: float, parameters: dict):
    k_pulse = int(round((RUN + offset) / H))
    n = k_pulse + 2
    initial = _run(h, H, set(), parameters, 1)[0]
    without = _run(h, H, set(), parameters, n)
    assert max(without[k_pulse - 3:]) < 0.2 * initial, "the identifier did not learn"
    with_pulse = _run(h, H, {k_pulse}, parameters, n)
    assert with_pulse[:k_pulse] == without[:k_pulse]
    assert with_pulse[k_pulse] > 0.5 * initial, (
        f"the reset pulse in step {k_pulse} (t = {k_pulse * H:g}, H = {H:g}, h = {h:g}) was "
        f"lost: trace(Gamma) {with_pulse[k_pulse]:g}, {initial:g} at a restart")


SHAPES = [(1e-3, 1e-4), (1e-3, 2.5e-4), (1e-3, 7e-4), (1e-3, 1e-3), (1e-4, 1e-3), (1e-4, 1.5e-4),
          (1e-3, 3e-5), (1e-3, 1.1e-3), (1e-4, 2.5e-4)]
OFFSETS = [0.0, 3e-4, 7.7e-4]
IDENTIFIERS = [{"identifier": 1, "identifier_form": 1}, {"identifier": 1, "identifier_form": 2},
               {"identifier": 2, "identifier_form": 2}]
CASES = [(h, H, o, p) for h, H in SHAPES for o in OFFSETS for p in IDENTIFIERS
         if not (p["identifier"] == 2 and o != OFFSETS[1])]


@pytest.mark.parametrize("h, H, offset, parameters", CASES,
                         ids=[f"h={c[0]:g}-H={c[1]:g}-at+{c[2]:g}-id{c[3]['identifier']}"
                              f"form{c[3]['identifier_form']}" for c in CASES])
def test_a_one_step_reset_pulse_restarts_identification(h, H, offset, parameters):
    isolated(_pulse, h, H, offset, parameters)


def _levels(h: float, H: float):
    """Only a rising edge restarts: not a level held high, not the falling edge."""
    parameters = IDENTIFIERS[1]
    k_up = int(round(RUN / H))
    k_down = k_up + max(3, int(round(0.2 / H)))
    n = k_down + 2
    initial = _run(h, H, set(), parameters, 1)[0]
    held = _run(h, H, set(range(k_up, k_down)), parameters, n)
    assert held[k_up] > 0.5 * initial  # the rising edge
    assert held[k_down - 1] < 0.5 * initial, "a level held high restarted again"
    assert held[k_down + 1] < 0.5 * initial, "the falling edge restarted"


@pytest.mark.parametrize("h, H", [(1e-3, 1e-4), (1e-4, 1e-3), (1e-3, 1e-3)])
def test_only_rising_edges_restart(h, H):
    isolated(_levels, h, H)
