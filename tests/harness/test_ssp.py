"""The closed loop as an SSP file that fmpy's SSP support loads and simulates."""
from __future__ import annotations

import numpy as np
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import read_ssd

from harness.ssp import write_ssp


def test_ssp_loads_and_simulates_in_fmpy(tmp_path, observer_fmu, pendulum_fmu, controller_fmu):
    ssp = write_ssp(observer_fmu.parent, tmp_path / "ClosedLoop.ssp", "6.2")
    ssd = read_ssd(str(ssp))  # validates against the SSP schema
    names = sorted(c.name for c in ssd.system.elements)
    assert names == ["controller", "observer", "plant"]
    assert len(ssd.system.connections) == 5
    # the scenario's parameters are bound inline per component
    observer = next(c for c in ssd.system.elements if c.name == "observer")
    values = {p.name: p.value for p in observer.parameterBindings[0].parameterValues[0].parameters}
    assert float(values["c_nominal[1]"]) == 2.0
    result = simulate_ssp(str(ssp), stop_time=0.05, step_size=1e-4)
    theta = result["plant.theta"]
    assert np.all(np.isfinite(theta))
    assert np.ptp(theta) > 1e-3  # the loop moved the pendulum
