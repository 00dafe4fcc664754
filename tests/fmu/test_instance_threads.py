"""Instances used from several threads at once (one instance per thread) give
exactly the results of the same runs one after the other.

ctypes releases the GIL during every foreign call, so the FMUs' code runs
truly in parallel here: any global or static mutable state in the FMI layer
or a model would show as a difference (or as a crash).
"""
from __future__ import annotations

import ctypes
import math
import threading

import numpy as np
import pytest

from tools.abuse.abuse_fmi import MODELS, OK, Raw, fmu_dir

THREADS = 4
_LOADING = threading.Lock()
OBS, PEN, CTL, ROBOT, *_ = MODELS

# Per model: parameters that differ per thread, an input signal, and the outputs read.
SETUPS = {
    OBS: (lambda i: {"identifier": 1 + i % 2, "tau": 0.002 * (1 + i), "identifier_start": 0},
          lambda i, t: {"y[1]": 0.3 * math.sin((2 + i) * t) + 0.1 * t, "u": math.cos(t)},
          ["x1_hat[1]", "x2_hat[1]", "z_eq_filtered[1]", "theta_hat[1,1]", "theta_hat[1,2]",
           "gamma_trace"]),
    PEN: (lambda i: {"damping": i % 2, "disturbance": i % 3, "theta_start": 0.1 * i},
          lambda i, t: {"u": math.sin((1 + i) * t)},
          ["theta", "omega", "acceleration"]),
    CTL: (lambda i: {"k1": 10.0 + i, "w1": 1.0 + i},
          lambda i, t: {"theta": 0.2 * math.sin(t * (1 + i)), "omega": 0.1 * math.cos(t)},
          ["u", "theta_d", "omega_d"]),
    # f+ above the default arm's accelerations: its inputs here are not a motion of it
    ROBOT: (lambda i: {"identifier": 1 + i % 2, "tau": 0.002 * (1 + i), "t_id": 0.0,
                       "f_plus[1]": 1e4, "f_plus[2]": 1e4},
            lambda i, t: {"q[1]": 0.3 * math.sin((2 + i) * t), "q[2]": 0.2 * math.cos(t),
                          "u[1]": 0.1 * math.cos(t), "u[2]": 0.05 * math.sin(t)},
            ["q_hat[1]", "qd_hat[1]", "qd_hat[2]", "base_estimate[1]", "gamma_trace"]),
    # the pendulum's model file (the template's resources)
    "ModelObserver": (lambda i: {"identifier": 1 + i % 2, "tau_identifier": 0.01 * (1 + i)},
                      lambda i, t: {"position_1": 0.3 * math.sin((2 + i) * t),
                                    "input_1": math.cos(t)},
                      ["position_estimate_1", "velocity_1", "theta_1", "theta_2"]),
}


def life(model: str, i: int, steps: int = 400, H: float = 1e-2) -> np.ndarray:
    """A whole life of one instance: init, steps with inputs, an FMU state saved,
    serialized, restored and replayed, a reset and a second short run."""
    parameters, inputs, outputs = SETUPS[model]
    with _LOADING:  # fmpy's FMU2Slave changes the working directory while it loads
        f = Raw(model, f"thread{i}")
    try:
        assert f.initialize(parameters(i)) == OK, f.messages()
        rows = []
        state = None
        for k in range(steps):
            t = k * H
            if k == steps // 2:
                state = f.get_state()
                data = f.serialize(state)
            assert f.set(inputs(i, t)) == OK
            assert f.do_step(t, H) == OK, f.messages()
            status, values = f.get_real(outputs)
            assert status == OK
            rows.append(values)
        # back to the middle through the serialized copy, and the second half again
        status, restored = f.deserialize(data)
        assert status == OK and f.call("fmi2SetFMUstate", restored) == OK
        for k in range(steps // 2, steps):
            t = k * H
            assert f.set(inputs(i, t)) == OK and f.do_step(t, H) == OK
            rows.append(f.get_real(outputs)[1])
        for s in (state, restored):
            assert f.call("fmi2FreeFMUstate", ctypes.byref(s)) == OK
        assert f.call("fmi2Reset") == OK
        assert f.initialize(parameters(i)) == OK
        for k in range(steps // 4):
            assert f.set(inputs(i, k * H)) == OK and f.do_step(k * H, H) == OK
            rows.append(f.get_real(outputs)[1])
        return np.array(rows)
    finally:
        f.free()


def in_threads(work) -> list:
    """Runs work(i) for i < THREADS, all threads released at once; re-raises failures."""
    results: list = [None] * THREADS
    errors: list = []
    barrier = threading.Barrier(THREADS)

    def run(i):
        try:
            barrier.wait()
            results[i] = work(i)
        except BaseException as error:  # noqa: BLE001
            errors.append(error)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(THREADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if errors:
        raise errors[0]
    return results


@pytest.mark.parametrize("model", MODELS)
def test_one_instance_per_thread_equals_sequential(model):
    sequential = [life(model, i) for i in range(THREADS)]
    assert not np.array_equal(sequential[0], sequential[1])  # the threads do differ
    for attempt in range(3):
        parallel = in_threads(lambda i: life(model, i))
        for i in range(THREADS):
            np.testing.assert_array_equal(parallel[i], sequential[i],
                                          err_msg=f"thread {i}, attempt {attempt}")


def test_all_fmus_mixed_across_threads():
    """Each thread drives instances of all three FMUs (12 live instances of 3 libraries)."""
    def work(i):
        return [life(m, i, steps=200) for m in MODELS]
    sequential = [work(i) for i in range(THREADS)]
    parallel = in_threads(work)
    for i in range(THREADS):
        for m in range(3):
            np.testing.assert_array_equal(parallel[i][m], sequential[i][m])


def test_closed_loops_in_threads_equal_sequential():
    """Scenario 6.2 closed loops through the harness's native loop (one C call per
    chunk, GIL released), each thread with its own three instances and noise seed."""
    from harness.master import initialize, run
    from harness.scenarios import COMMUNICATION_STEP, PROBES, SCENARIOS, build

    s = SCENARIOS["6.2"]
    seconds = 0.5
    n = int(round(seconds / COMMUNICATION_STEP))

    def prepared(i):
        noise = np.random.default_rng(i).normal(0.0, 1e-4, n)
        sim = build(s, fmu_dir())
        initialize(sim, 0.0, {"plant": s.plant, "controller": s.controller,
                              "observer": s.observer}, {"noise": noise})
        return sim, noise

    def go(sim, noise):
        try:
            return run(sim, 0.0, seconds, COMMUNICATION_STEP, PROBES, decimation=10,
                       signals={"noise": noise}, use_native=True)
        finally:
            sim.close()

    sequential = [go(*prepared(i)) for i in range(THREADS)]
    ready = [prepared(i) for i in range(THREADS)]  # fmpy's loading is not thread-safe (chdir)
    parallel = in_threads(lambda i: go(*ready[i]))
    for i in range(THREADS):
        for name in PROBES:
            np.testing.assert_array_equal(parallel[i][name], sequential[i][name],
                                          err_msg=f"thread {i}: {name}")
