"""The cross-validation's input score (harness.model.held_out_inputs) and how the pipeline
is picked from it and the simulation score (harness.model.selection.pick)."""
from __future__ import annotations

import numpy as np

from harness.model import read_model
from harness.model.held_out_inputs import REFERENCE_ROWS, HeldOutInputs
from harness.model.log import read_log
from harness.model.selection import FOLDS, combined_scores, pick

OSCILLATOR = """\
[model]
coordinates = ["x"]
inputs = ["u"]
equations = ["m*der(x,2) + d*der(x) + k*x = u"]

[parameters]
m = { nominal = 1 }
d = { nominal = 1 }
k = { nominal = 100 }
"""
TRUTH = np.array([2.0, 3.0, 400.0])


def test_the_input_score_sees_an_inertia_error(tmp_path):
    """A linear oscillator's exact log: the truth reconstructs the input of every block
    about as well as the reference's own least squares, a mass 10 % off many times worse."""
    t = np.arange(6000) / 500.0
    w = 2 * np.pi * np.array([0.3, 0.7, 1.3, 2.1])
    x = np.sin(np.outer(t, w)).sum(axis=1) / 400.0
    xd = (w * np.cos(np.outer(t, w))).sum(axis=1) / 400.0
    xdd = -(w ** 2 * np.sin(np.outer(t, w))).sum(axis=1) / 400.0
    u = TRUTH[0] * xdd + TRUTH[1] * xd + TRUTH[2] * x
    np.savetxt(tmp_path / "log.csv", np.column_stack([t, x, u]), delimiter=",",
               header="t,x,u", comments="")
    (tmp_path / "m.toml").write_text(OSCILLATOR)
    model = read_model(tmp_path / "m.toml")
    log = read_log(tmp_path / "log.csv", model)
    edges = np.linspace(0, log.samples, FOLDS + 1).round().astype(int)
    inputs = HeldOutInputs(model, log, edges)
    truth = inputs.scores(np.tile(TRUTH, (FOLDS, 1)))
    heavy = inputs.scores(np.tile(TRUTH * [1.1, 1.0, 1.0], (FOLDS, 1)))
    assert truth.shape == (FOLDS,) and np.mean(truth) < 1.0, truth
    assert np.all(heavy > 10 * truth), heavy / truth
    missing = np.tile(TRUTH, (FOLDS, 1))
    missing[2] = np.nan  # a block without an estimate cannot be scored
    assert np.isinf(inputs.scores(missing)[2])


def blocks(*values: float) -> np.ndarray:
    return np.array(values, dtype=float)


def test_the_input_score_decides_where_the_runs_cannot_tell():
    """The two-link arm's 40 s log (bench/cases/two_link.py), rounded: the 20 Hz IDIM-LS
    pipeline's runs score a little better, but its input error is 5 times the 4 Hz
    pipeline's (joint 1's torque on the validation run: 10 % and 3.6 %)."""
    runs = {"20 Hz": blocks(2.6, 2.3, 1.7, 3.9, 2.4), "4 Hz": blocks(2.9, 2.6, 1.6, 4.0, 2.9)}
    inputs = {"20 Hz": blocks(5.1, 5.8, 4.9, 6.0, 5.6), "4 Hz": blocks(1.0, 0.9, 1.0, 1.0, 0.9)}
    assert pick(runs, combined_scores(runs, inputs)) == "4 Hz"
    assert pick(runs, combined_scores(runs, {})) == "20 Hz"  # the runs alone


def test_the_runs_decide_where_the_inputs_cannot_tell():
    """EMPS: every candidate reconstructs the input within 2 % of the others; the runs'
    choice stands. The cubic oscillator: the input score prefers a cut-off below the
    resonance, whose runs are 26 times worse; the runs' choice stands."""
    runs = {"spectral 100 Hz": blocks(3.3, 3.4, 3.2, 3.3, 3.4),
            "IDIM-LS": blocks(3.35, 3.3, 3.4, 3.3, 3.4)}
    inputs = {"spectral 100 Hz": blocks(1.02, 1.01, 1.02, 1.03, 1.01),
              "IDIM-LS": blocks(1.00, 1.00, 1.01, 1.00, 1.00)}
    combined = combined_scores(runs, inputs)
    assert np.mean(combined["IDIM-LS"]) < np.mean(combined["spectral 100 Hz"])  # by 0.7 %
    assert pick(runs, combined) == "spectral 100 Hz"
    runs = {"244 Hz": blocks(2.2, 2.4, 2.1, 2.3, 2.3), "61 Hz": blocks(55, 62, 58, 66, 60)}
    inputs = {"244 Hz": blocks(1.3, 1.4, 1.3, 1.35, 1.37), "61 Hz": blocks(1, 1, 1, 1, 1)}
    assert pick(runs, combined_scores(runs, inputs)) == "244 Hz"


def test_no_finite_candidate_is_no_choice():
    runs = {"a": np.full(FOLDS, np.inf), "b": blocks(1, 1, np.inf, 1, 1)}
    assert pick(runs, combined_scores(runs, {})) is None
    assert combined_scores(runs, {})["b"][2] == np.inf


FRICTION = """\
[model]
coordinates = ["x"]
inputs = ["u"]
equations = ["m*der(x,2) + d*der(x) + c*sign(der(x)) = u"]

[parameters]
m = { nominal = 1 }
d = { nominal = 1 }
c = { nominal = 1 }
"""


def friction_log(tmp_path, frequency: float, name: str):
    """A mass with Coulomb friction on a sine of ``frequency`` [Hz], 200 Hz, 30 s, its
    positions with 1 mm of noise (whose floor sets a cut-off of a few hertz)."""
    t = np.arange(6000) / 200.0
    w = 2 * np.pi * frequency
    x, xd, xdd = 2 * np.sin(w * t), 2 * w * np.cos(w * t), -2 * w * w * np.sin(w * t)
    u = 2.0 * xdd + 0.5 * xd + 0.3 * np.sign(xd)
    noise = 1e-3 * np.random.default_rng(1).standard_normal(len(t))
    np.savetxt(tmp_path / name, np.column_stack([t, x + noise, u]), delimiter=",",
               header="t,x,u", comments="")
    (tmp_path / "m.toml").write_text(FRICTION)
    model = read_model(tmp_path / "m.toml")
    return model, read_log(tmp_path / name, model)


def test_the_reference_keeps_its_friction_rows_only_where_they_leave_the_log(tmp_path):
    """Its friction rows leave out a margin around each reversal that grows as its cut-off
    falls: with a reversal every 10 s they keep most rows; with one every 0.33 s, none,
    and the reference goes without them (every block is then scored)."""
    for frequency, kept in ((0.05, True), (1.5, False)):
        model, log = friction_log(tmp_path, frequency, f"{frequency}.csv")
        edges = np.linspace(0, log.samples, FOLDS + 1).round().astype(int)
        inputs = HeldOutInputs(model, log, edges)
        assert inputs.settings.friction_rows is kept, (frequency, inputs.settings)
        assert np.mean(inputs.mask) >= REFERENCE_ROWS
        scores = inputs.scores(np.tile([2.0, 0.5, 0.3], (FOLDS, 1)))
        assert np.all(np.isfinite(scores)), scores


def test_a_block_the_reference_leaves_out_is_not_scored(tmp_path):
    """A block in which the reference keeps no row scores NaN (not 0, which would be the
    best score), and the combination counts the simulation alone there."""
    model, log = friction_log(tmp_path, 0.05, "slow.csv")
    edges = np.linspace(0, log.samples, FOLDS + 1).round().astype(int)
    inputs = HeldOutInputs(model, log, edges)
    inputs.mask[inputs.owner == 1] = False
    scores = inputs.scores(np.tile([2.0, 0.5, 0.3], (FOLDS, 1)))
    assert np.isnan(scores[1]) and np.all(np.isfinite(np.delete(scores, 1)))
    runs = {"a": blocks(1, 1, 1, 1, 1), "b": blocks(2, 2, 2, 2, 2)}
    combined = combined_scores(runs, {"a": blocks(1, np.nan, 1, 1, 1),
                                      "b": blocks(1, np.nan, 1, 1, 1)})
    assert np.allclose(combined["a"], 1) and np.allclose(combined["b"], 2), combined
