"""The FMUs ship their sources: `fmpy compile` rebuilds a working binary from them."""
from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile

import numpy as np
from fmpy import simulate_fmu


def test_fmpy_compile_rebuilds_the_observer_from_its_sources(tmp_path, observer_fmu):
    rebuilt = tmp_path / "SuperTwistingObserver.fmu"
    shutil.copy(observer_fmu, rebuilt)
    # drop the shipped binary so that only the rebuilt one can be used
    stripped = tmp_path / "stripped.fmu"
    with zipfile.ZipFile(rebuilt) as src, zipfile.ZipFile(stripped, "w") as dst:
        for item in src.infolist():
            if not item.filename.startswith("binaries/"):
                dst.writestr(item, src.read(item.filename))
    stripped.replace(rebuilt)
    result = subprocess.run([sys.executable, "-m", "fmpy.cli", "compile", str(rebuilt)],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    assert "binaries/linux64/SuperTwistingObserver.so" in zipfile.ZipFile(rebuilt).namelist()
    t = np.arange(0.0, 0.2, 1e-4)
    signals = np.array(list(zip(t, 0.1 * np.sin(5 * t))), dtype=[("time", float), ("y[1]", float)])
    original = simulate_fmu(str(observer_fmu), stop_time=0.2, input=signals,
                            output=["x2_hat[1]"])
    result = simulate_fmu(str(rebuilt), stop_time=0.2, input=signals, output=["x2_hat[1]"])
    assert np.ptp(original["x2_hat[1]"]) > 0.1  # the input moved the observer
    np.testing.assert_allclose(result["x2_hat[1]"], original["x2_hat[1]"], rtol=1e-12, atol=1e-12)
