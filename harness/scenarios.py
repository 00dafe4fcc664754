"""The paper's section 6 examples as closed-loop scenarios.

Every choice the paper leaves open is written down here, next to its value,
with the reason (see ``Scenario.choices``; docs/scenarios.md prints them).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from .fmus import FMUInstance, Value
from .master import CoSimulation, Link

# The paper's pendulum, section 6.
M, G, L, VS, PS = 1.1, 9.815, 0.9, 0.18, 0.45
J = M * L * L
A_GRAVITY, A_VISCOUS, A_COULOMB = M * G * L / (2 * J), VS / J, PS / J

COMMUNICATION_STEP = 1e-4  # the paper's sampling step delta = 0.0001 (6.2)

# Shared choices (the paper is silent on them).
COMMON_CHOICES = {
    "communication step H = observer h = controller sample = 1e-4 s":
        "the paper's sampling time delta = 0.0001 s (section 6.2)",
    "plant internal step 1e-5 s, RK4, u held over H":
        "10 plant steps per sample make the plant 'continuous' relative to the observer",
    "plant starts at theta = 0.1 rad, omega = 0.5 rad/s":
        "not at rest and not on the reference, so the observer has a velocity error to remove",
    "observer starts at x1_hat = y(0), x2_hat = 0":
        "the position is measured; the initial velocity error (0.5 rad/s) shows finite-time "
        "convergence",
    "input: the twisting controller (44) with theta_d of (44) in every scenario":
        "6.1 does not say what drives the pendulum; the same loop as 6.2/6.3 keeps the runs "
        "comparable",
    "step order observer -> plant -> controller":
        "the observer integrates [t, t+H] with y(t), u(t), the samples the paper's explicit "
        "scheme uses",
}


@dataclass(frozen=True)
class Scenario:
    name: str
    title: str
    kind: str  # "perturbation", "lsm" or "mff"
    stop_time: float
    plant: dict[str, Value]
    observer: dict[str, Value]
    controller: dict[str, Value] = field(default_factory=dict)
    transient: float = 1.0  # metrics ignore t < transient
    choices: dict[str, str] = field(default_factory=dict)

    @property
    def c_true(self) -> list[float]:
        """True coefficients of the joint basis [sin x1, x2, sign x2, x1, 1] (d(t) aside)."""
        m, g, length = (float(self.plant.get(k, v)) for k, v in (("M", M), ("g", G), ("L", L)))
        j = m * length * length
        return [m * g * length / (2 * j), float(self.plant.get("Vs", VS)) / j,
                float(self.plant.get("Ps", PS)) / j, 0.0, 0.0]

    @property
    def c_nominal(self) -> list[float]:
        return [float(self.observer.get(f"c_nominal[{k}]", 0.0)) for k in range(1, 6)]


PLANT_START = {"theta_start": 0.1, "omega_start": 0.5}
# The paper's method exactly: explicit Euler observer and identifier, raw
# regressor, identification from t_id.  The FMU's defaults are the improved
# method; `improved` below switches a scenario to them.
PAPER_METHOD = {"scheme": 1, "identifier_form": 1, "filter_regressor": False,
                "identifier_start": 0, "identify_b": False}
# The improved method keeps the scenario's t_id as a lower bound on the start:
# with measurement noise the convergence test fires at the noise floor while
# the closed loop is still in its reaching phase (the first 0.5 s), whose data
# bias a2 by about 10 % at noise 1e-4 (1.9 % when starting at 1 s).
IMPROVED_METHOD = {"scheme": 3, "identifier_form": 2, "filter_regressor": True,
                   "identifier_start": 1, "identify_b": True}
PAPER_GAINS = {"alpha1[1]": 2.2211, "alpha2[1]": 19.1819}  # section 6.3
EXACT_NOMINAL = {"b": 1 / J, "c_nominal[1]": A_GRAVITY, "c_nominal[2]": A_VISCOUS,
                 "c_nominal[3]": 0.0, "c_nominal[4]": 0.0, "c_nominal[5]": 0.0}

SCENARIOS: dict[str, Scenario] = {}


def _add(s: Scenario) -> None:
    SCENARIOS[s.name] = s


_add(Scenario(
    name="6.1-sine", title="6.1 perturbation identification, v(t) = 0.5 sin 2t",
    kind="perturbation",
    stop_time=10.0,
    plant={**PLANT_START, "Ps": 0.0, "disturbance": 1, "v_amplitude": 0.5, "v_frequency": 2.0},
    observer={**PAPER_METHOD, **EXACT_NOMINAL, **PAPER_GAINS, "tau": 0.02, "identifier": 0,
              "f_plus[1]": 0.5},
    choices={
        "v(t) = 0.5 sin(2t)": "the paper shows a sinusoid without its parameters",
        "f_plus = 0.5": "the bound (5) on |v| with the exact nominal model; the paper's gains "
        "satisfy (6) for it (the FMU warns when they do not)",
        "tau = 0.02 s": "the paper's value for the sinusoidal perturbation",
        "gains alpha1 = 2.2211, alpha2 = 19.1819": "the only gains the paper gives (6.3); "
        "|v| <= 0.5 plus the O(h) mismatch stays below alpha1",
        "no Coulomb friction in the plant": "the 6.1 model has none",
        "run length 10 s": "five periods of v after the transient",
    }))

_add(Scenario(
    name="6.1-square", title="6.1 perturbation identification, v(t) = 0.5 sign(sin t)",
    kind="perturbation", stop_time=10.0,
    plant={**PLANT_START, "Ps": 0.0, "disturbance": 2, "v_amplitude": 0.5,
           "v_period": 2 * math.pi},
    observer={**PAPER_METHOD, **EXACT_NOMINAL, **PAPER_GAINS, "tau": 0.002, "identifier": 0,
              "f_plus[1]": 0.5},
    choices={
        "v(t) = 0.5 sign(sin t)": "the paper shows a square wave without its parameters",
        "f_plus = 0.5": "the bound (5) on |v| with the exact nominal model",
        "tau = 0.002 s": "the paper's value for the discontinuous perturbation",
        "RMS measured away from the jumps (from 5 ms before to 50 ms after each)":
            "the filter cannot follow a jump; what matters is the level between jumps",
    }))

_add(Scenario(
    name="6.2", title="6.2 time-invariant parameters, LSM", kind="lsm", stop_time=40.0,
    plant={**PLANT_START},
    observer={**PAPER_METHOD, "b": 1 / J, "c_nominal[1]": 2.0, "c_nominal[2]": 0.1,
              "c_nominal[3]": 0.1, "c_nominal[4]": 0.0, "c_nominal[5]": 0.0,
              "alpha1[1]": 8.0, "alpha2[1]": 24.0, "f_plus[1]": 4.5, "p[1]": 0.2, "tau": 0.002,
              "identifier": 1, "t_id": 1.0, "rho": 1e-3,
              "identify[1]": True, "identify[2]": True, "identify[3]": True},
    choices={
        "nominal a1, a2, a3 = 2, 0.1, 0.1": "the paper's values",
        "gains alpha1 = 8, alpha2 = 24": "|xi| <= 3.45 + 0.1 |x2| + 0.41 < 4.5 = f+ here; "
        "alpha1 = 8 > f+ and alpha2 above the bound of (6) with p = 0.2 (14.2) keep the O(h) "
        "velocity bias small (it grows with alpha2)",
        "tau = 0.002 s": "the paper does not say; the O(tau) lag of the filtered injection "
        "against the unfiltered regressor biases a2, a3 by about 1.5 percent at 2 ms versus "
        "7-14 percent at 20 ms",
        "identifier starts at t_id = 1 s": "after the observer has converged (0.15-0.55 s); "
        "starting at 0 integrates the observer transient and leaves a2 off by more than 100 "
        "percent",
        "rho = 1e-3 (Gamma(0) = 1000 I)": "small regularization; explicit Euler on Gamma "
        "stays stable since h |Gamma| |phi|^2 << 2",
        "run length 40 s": "the figure the issue quotes is at 40 s",
    }))

_add(Scenario(
    name="6.3", title="6.3 time-varying damping, MFF", kind="mff", stop_time=50.0,
    plant={**PLANT_START, "Vs": 0.0, "damping": 1},
    observer={**PAPER_METHOD, "b": 1 / J, "c_nominal[1]": A_GRAVITY, "c_nominal[2]": 0.0,
              "c_nominal[3]": A_COULOMB, "c_nominal[4]": 0.0, "c_nominal[5]": 0.0,
              **PAPER_GAINS, "f_plus[1]": 1.2, "tau": 0.002, "identifier": 2, "R": 0.1,
              "t_id": 1.0, "rho": 1e-3,
              "identify[1]": False, "identify[2]": True, "identify[3]": False},
    transient=5.0,
    choices={
        "R = 0.1, alpha1 = 2.2211, alpha2 = 19.1819": "the paper's values",
        "f_plus = 1.2": "|d(t) x2| stays below 1.13 rad/s2 in this loop (measured); the paper's "
        "gains satisfy (6) for it",
        "the estimate published is d(t) itself": "theta_hat[1,2] estimates c_2 in "
        "x'' = ... - c_2 x2, i.e. d(t); the paper's vartheta = -d(t) (its z_eq line has the "
        "sign slipped)",
        "tau = 0.002 s, rho = 1e-3, t_id = 1 s": "as in 6.2",
        "run length 50 s": "more than one period (2 pi 7 = 44 s) of d(t)",
        "metrics after 5 s": "the issue's convention for the MFF error",
    }))


def all_choices(s: Scenario) -> dict[str, str]:
    return {**COMMON_CHOICES, **s.choices}


def bench_links() -> list[Link]:
    """The closed loop: plant -> controller -> plant, plant and controller -> observer."""
    return [
        Link("controller.u", "plant.u"),
        Link("plant.theta", "controller.theta"),
        Link("plant.omega", "controller.omega"),
        Link("plant.theta", "observer.y[1]", noise="noise"),
        Link("controller.u", "observer.u"),
    ]


def build(s: Scenario, fmu_dir: Path) -> CoSimulation:
    """Instantiate the three FMUs of a scenario (data-flow order) and wire them."""
    fmus = {
        "plant": FMUInstance(fmu_dir / "Pendulum.fmu", "plant"),
        "controller": FMUInstance(fmu_dir / "TwistingController.fmu", "controller"),
        "observer": FMUInstance(fmu_dir / "SuperTwistingObserver.fmu", "observer"),
    }
    return CoSimulation(fmus, bench_links(), step_order=["observer", "plant", "controller"])


PROBES = [
    "plant.theta", "plant.omega", "plant.acceleration", "plant.v", "plant.d",
    "controller.u", "controller.theta_d",
    "observer.x1_hat[1]", "observer.x2_hat[1]", "observer.z_eq_filtered[1]",
    "observer.theta_hat[1,1]", "observer.theta_hat[1,2]", "observer.theta_hat[1,3]",
    "observer.gamma_trace",
]


def run_on(sim: CoSimulation, s: Scenario, *, noise_std: float = 0.0, seed: int = 0,
           observer_overrides: dict[str, Value] | None = None, use_native: bool | None = None,
           progress=None):
    """Initialize instantiated (or reset) FMUs for a scenario and run it; returns the
    Records of PROBES at every communication step."""
    import numpy as np

    from .master import initialize, run

    n_steps = int(round(s.stop_time / COMMUNICATION_STEP))
    noise = (np.random.default_rng(seed).normal(0.0, noise_std, n_steps) if noise_std > 0
             else np.zeros(n_steps))
    parameters = {"plant": s.plant, "controller": s.controller,
                  "observer": {**s.observer, **(observer_overrides or {})}}
    initialize(sim, 0.0, parameters, {"noise": noise})
    return run(sim, 0.0, s.stop_time, COMMUNICATION_STEP, PROBES, signals={"noise": noise},
               use_native=use_native, progress=progress)


def run_scenario(s: Scenario, fmu_dir: Path, **options):
    """Run one scenario on fresh FMUs (options as for run_on)."""
    sim = build(s, fmu_dir)
    try:
        return run_on(sim, s, **options)
    finally:
        sim.close()


# The improved method runs with the FMU's default filter constant at every
# noise level: nothing about the sensor is declared (scheme 3 estimates the
# noise itself and publishes the linear member that suits it).
IMPROVED_TAU = 0.002


def improved_overrides(s: Scenario, noise_std: float = 0.0) -> dict[str, Value]:
    """Observer parameters that switch a scenario from the paper's method to the FMU's
    defaults (the same for every scenario and noise level; the arguments are kept for
    the callers that pass them)."""
    del s, noise_std
    return {**IMPROVED_METHOD, "tau": IMPROVED_TAU}
