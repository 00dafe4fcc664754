"""bench/perf/robot_step_cost.py --fmu: the driver of the RobotObserver FMU's internal step
builds with the FMU's flags, sets a 7-joint robot's parameters by value reference, and
the step it measures is the identifying one (not a timing test)."""
from __future__ import annotations

import re

import pytest

from bench.perf import robot_step_cost as cost


@pytest.fixture(scope="module")
def panda(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("robot_fmu_step")
    binary = tmp / "robot_fmu_step"
    cost.build(binary, None, fmu=True)  # -Wall -Wextra -Wpedantic -Werror -O2
    return binary, cost.fmu_files("panda", tmp, cost.FMU_WARMUP + 300)


def test_the_panda_fmu_step_runs_identifying_all_base_parameters(panda):
    binary, files = panda
    assert files[2:] == (7, 57)  # n, and base_count: every base parameter and friction
    for steps, calls in ((1, 200), (200, 1)):  # H = h, and one doStep of 200 h
        run = cost.fmu_run(binary, files, steps, calls)  # raises unless identifying
        assert run["ns"] > 0.0 and run["slowest"] > 0.0


def test_a_run_that_does_not_reach_t_id_is_refused(panda):
    binary, files = panda
    text = files[0].read_text()
    assert re.search(r"^R 9 0\.02$", text, re.M)  # t_id, value reference 9
    late = files[0].with_name("late.parameters")
    late.write_text(re.sub(r"^R 9 0\.02$", "R 9 100.0", text, flags=re.M))
    with pytest.raises(RuntimeError, match="identifier_active=0"):
        cost.fmu_run(binary, (late, *files[1:]), 1, 10)
