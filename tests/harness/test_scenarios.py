"""The paper's section 6 reproduced, and the improved method, pinned by their metrics.

The bounds sit around the figures measured when this test was written
(docs/scenarios.md, docs/design/observer.md), so that a regression fails.
"""
from __future__ import annotations

import pytest

from harness.metrics import score
from harness.scenarios import SCENARIOS, improved_overrides, run_scenario

# scenario -> metric -> (low, high); measured values in the comments
PAPER_BOUNDS = {
    "6.1-sine": {"rms_perturbation": (0.02, 0.05),       # 0.0355
                 "delay": (0.015, 0.045),                # 0.033
                 "max_e2_after_1s": (2e-3, 1.5e-2),      # 7.8e-3
                 "convergence_time": (0.1, 0.6)},        # 0.22
    "6.1-square": {"rms_perturbation": (0.05, 0.2),      # 0.119
                   "max_e2_after_1s": (2e-3, 1.5e-2)},   # 7.7e-3
    "6.2": {"a1_rel_error_end": (0.0, 0.002),            # 5.1e-4
            "a2_rel_error_end": (0.002, 0.05),           # 9.9e-3
            "a3_rel_error_end": (0.02, 0.08),            # 0.048
            "max_e2_after_1s": (5e-3, 3e-2),             # 1.4e-2
            "convergence_time": (0.01, 0.6)},            # 0.054
    "6.3": {"rms_damping": (0.02, 0.05),                 # 0.033
            "damping_lag": (0.35, 0.6),                  # 0.48
            "max_e2_after_1s": (5e-3, 2e-2)},            # 1.0e-2
}

IMPROVED_BOUNDS = {
    # The FMU's defaults, tau = 2 ms included (with tau = 0.5 ms: 4.8e-4 and 0.6 ms,
    # test_a_shorter_filter_follows_the_perturbation_closer)
    "6.1-sine": {"rms_perturbation": (0.0, 0.002),       # 1.5e-3 (goal 0.005)
                 "delay": (0.0, 0.003),                  # 2.2 ms (goal 5 ms)
                 "max_e2_after_1s": (0.0, 1e-5)},        # 1.2e-7
    "6.1-square": {"rms_perturbation": (0.0, 0.002),     # 1.9e-4
                   "max_e2_after_1s": (0.0, 3e-4)},      # 1.2e-4
    # 6.2 with tau_identifier = 0.1 s (the LSM regression's filter) and model_feedback:
    # a2 at 20 s is within the goal by 0.7 % (3.3e-4 with tau's 2 ms, 9.5e-4
    # without the feedback; at the end 5.3e-4)
    "6.2": {"a1_rel_error_20s": (0.0, 1e-3),             # 4.3e-4 (goal 1e-3 at 20 s)
            "a2_rel_error_20s": (0.0, 1e-3),             # 9.9e-4
            "a3_rel_error_20s": (0.0, 1e-3),             # 4.6e-4
            "max_e2_after_1s": (0.0, 2e-4)},             # 3.3e-5 (goal 1e-4)
    "6.3": {"rms_damping": (0.0, 0.006),                 # 2.5e-3 (goal 0.01)
            "damping_lag": (0.0, 0.04),                  # 21 ms (goal 0.1 s)
            "max_e2_after_1s": (0.0, 3e-4)},             # 1.3e-4
}


@pytest.fixture(scope="module")
def fmu_dir(observer_fmu, pendulum_fmu, controller_fmu):
    return observer_fmu.parent


@pytest.mark.parametrize("name", list(PAPER_BOUNDS))
def test_paper_method_reproduces_section_6(fmu_dir, name):
    s = SCENARIOS[name]
    metrics = score(s, run_scenario(s, fmu_dir))
    for metric, (low, high) in PAPER_BOUNDS[name].items():
        assert low <= metrics[metric] <= high, f"{name} {metric} = {metrics[metric]:.4g}"


@pytest.mark.parametrize("name", list(IMPROVED_BOUNDS))
def test_improved_method_reaches_its_goals(fmu_dir, name):
    s = SCENARIOS[name]
    metrics = score(s, run_scenario(s, fmu_dir, observer_overrides=improved_overrides(s)))
    for metric, (low, high) in IMPROVED_BOUNDS[name].items():
        assert low <= metrics[metric] <= high, f"{name} {metric} = {metrics[metric]:.4g}"


def test_a_shorter_filter_follows_the_perturbation_closer(fmu_dir):
    """Noise-free, the implicit injection does not chatter: tau = 0.5 ms is enough."""
    s = SCENARIOS["6.1-sine"]
    metrics = score(s, run_scenario(s, fmu_dir,
                                    observer_overrides={**improved_overrides(s), "tau": 5e-4}))
    assert metrics["rms_perturbation"] < 0.001  # 4.8e-4
    assert metrics["delay"] <= 0.001            # 0.6 ms
