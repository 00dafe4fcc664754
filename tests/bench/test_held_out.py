"""The held-out joints (bench/reports/realdata/held_out.py) and the accurate plant's long sticks."""
from __future__ import annotations

import numpy as np
import pytest

from bench.reports.realdata import held_out, plants, sensors


def test_a_short_pulse_during_a_long_stick_breaks_the_joint_away():
    # A drive above static friction for 20 ms only, 5 s into a stick: a solver whose
    # steps grow freely while nothing moves steps over it and the joint never moves.
    c = (0.0, 0.0, 1.0)
    b = 2.0

    def pulse(t):  # noqa: ANN001, ANN202 -- b u peaks at 1.5 c3 around t = 5 s
        return 1.5 * c[2] / b * np.exp(-0.5 * ((np.asarray(t, dtype=float) - 5.0) / 0.01) ** 2)

    data = plants.open_loop_accurate(1000, 6.0, torque=pulse, c=c, b=b, name="pulse")
    assert np.all(data.x2[data.t < 4.9] == 0.0)
    assert np.max(data.x2) > 1e-3  # it moved during the pulse
    assert data.meta["stuck_segments"] >= 2  # stuck, moving, stuck again


@pytest.mark.parametrize("name", list(held_out.PLANTS))
def test_held_out_joints_obey_their_own_model(name):
    p = held_out.PLANTS[name]
    data = plants.open_loop_accurate(1000, 8.0, torque=p.torque, c=p.c, b=p.b, name=name)
    assert data.name == name and data.b == p.b and data.c == p.c
    moving = data.x2 != 0
    model = (p.b * data.u - p.c[0] * np.sin(data.x1) - p.c[1] * data.x2
             - p.c[2] * np.sign(data.x2))
    assert np.allclose(data.acc[moving], model[moving], atol=1e-9 * np.max(np.abs(data.acc)))
    # the velocity is the derivative of the angle (central differences, to their accuracy)
    dv = np.gradient(data.x1, data.step)
    assert np.sqrt(np.mean((dv - data.x2) ** 2)) < 0.01 * np.sqrt(np.mean(data.x2 ** 2))
    assert np.max(np.abs(data.x1)) < 0.8 * np.pi  # swings, never over the top


def test_the_held_out_grid_names_only_known_sensors_and_rates():
    for meas in held_out.MEASUREMENTS:
        sensors.measurement(meas)  # raises KeyError for an unknown name
    assert sensors.measurement("enc-16+noise-1e-4").label == "16-bit encoder + noise 1e-04"
    assert sensors.model_error(sensors.HELD_OUT_MODEL.name) is sensors.HELD_OUT_MODEL
    assert all(held_out.SIMULATION_RATE % rate == 0 for rate in held_out.RATES)
    b, c = sensors.nominal(sensors.HELD_OUT_MODEL, 500.0, (60.0, 2.0, 8.0))
    assert b == pytest.approx(500.0 / 1.1)
    assert c == pytest.approx((60.0 / 1.1, 2.0 / 2.2, 8.0 / 2.2))
