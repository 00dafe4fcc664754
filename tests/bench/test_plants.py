"""The open-loop plant kinds with a torque that stops, a damping d(t) and the final stop
into static friction (bench/reports/no_excitation.py's data)."""
from __future__ import annotations

import numpy as np
import pytest

from bench.reports.realdata import plants
from harness.scenarios import A_COULOMB, A_GRAVITY

C = (A_GRAVITY, 0.0, A_COULOMB)
OFF = 3.0  # s: the torque stops


def _torque(t):  # noqa: ANN001, ANN202
    t = np.asarray(t, dtype=float)
    return np.where(t < OFF, plants.multisine(t), 0.0)


def _damping(t):  # noqa: ANN001, ANN202
    return 0.5 + 0.2 * np.sin(np.asarray(t, dtype=float))


@pytest.fixture(scope="module")
def kinds():
    options = {"torque": _torque, "c": C, "damping": _damping}
    return {"accurate": plants.open_loop_accurate(1000, 12.0, breaks=(OFF,), **options),
            "rk45-1e-6": plants.open_loop_rk45("rk45-1e-6", 1000, 12.0, stop_after=OFF,
                                               **options),
            "euler": plants.open_loop_euler(1000, 12.0, **options)}


def test_every_kind_comes_to_rest_inside_the_static_friction_band(kinds):
    for kind, data in kinds.items():
        tail = data.t >= 11.0
        # Euler chatters about x2 = 0 by at most h (c3 + |c1 sin x|) <= 2 h c3
        assert np.max(np.abs(data.x2[tail])) <= 2 * data.step * C[2], kind
        assert abs(C[0] * np.sin(data.x1[-1])) <= C[2], kind
    for kind in ("accurate", "rk45-1e-6"):  # at rest: not a sample moves
        assert np.ptp(kinds[kind].x1[kinds[kind].t >= 11.0]) == 0.0
        assert kinds[kind].x2[-1] == 0.0
    # explicit Euler does not stick: its chatter about x2 = 0 has a mean, it creeps
    euler = kinds["euler"]
    creep = np.mean(euler.x2[euler.t >= 11.0])
    assert 1e-5 < abs(creep) < 1e-3


def test_the_kinds_agree_with_the_accurate_trajectory_to_their_accuracy(kinds):
    ref = kinds["accurate"]
    assert np.allclose(kinds["rk45-1e-6"].x1, ref.x1, atol=1e-4)
    assert kinds["rk45-1e-6"].meta["rest_from"] == pytest.approx(ref.t[np.nonzero(ref.x2)[0][-1]],
                                                                 abs=0.01)
    assert np.allclose(kinds["euler"].x1, ref.x1, atol=0.05)
    assert not np.allclose(kinds["euler"].x1, ref.x1, atol=1e-3)  # Euler at 1 ms is coarse
    # the damping is in the dynamics: the recorded acceleration satisfies the model
    moving = ref.x2 != 0
    model = (ref.b * ref.u - C[0] * np.sin(ref.x1) - C[2] * np.sign(ref.x2)
             - _damping(ref.t) * ref.x2)
    assert np.allclose(ref.acc[moving], model[moving], atol=1e-12)
    assert np.allclose(ref.d, _damping(ref.t))
