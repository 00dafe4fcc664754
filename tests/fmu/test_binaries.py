"""The shared libraries export the FMI 2.0 functions and nothing else, and need only libc/libm."""
from __future__ import annotations

import subprocess
import zipfile

import pytest

COMMON = """GetTypesPlatform GetVersion SetDebugLogging Instantiate FreeInstance SetupExperiment
EnterInitializationMode ExitInitializationMode Terminate Reset GetReal GetInteger GetBoolean
GetString SetReal SetInteger SetBoolean SetString GetFMUstate SetFMUstate FreeFMUstate
SerializedFMUstateSize SerializeFMUstate DeSerializeFMUstate GetDirectionalDerivative""".split()
COSIMULATION = """SetRealInputDerivatives GetRealOutputDerivatives DoStep CancelStep GetStatus
GetRealStatus GetIntegerStatus GetBooleanStatus GetStringStatus""".split()


@pytest.mark.parametrize("model", ["SuperTwistingObserver", "Pendulum", "TwistingController"])
def test_exports_and_dependencies(tmp_path, observer_fmu, model):
    fmu = observer_fmu.parent / f"{model}.fmu"
    library = tmp_path / f"{model}.so"
    library.write_bytes(zipfile.ZipFile(fmu).read(f"binaries/linux64/{model}.so"))
    symbols = subprocess.run(["nm", "-D", "--defined-only", str(library)], capture_output=True,
                             text=True, check=True).stdout.split("\n")
    exported = {line.split()[-1] for line in symbols if line.strip()}
    assert exported == {f"fmi2{name}" for name in COMMON + COSIMULATION}
    needed = subprocess.run(["objdump", "-p", str(library)], capture_output=True, text=True,
                            check=True).stdout
    libraries = {line.split()[-1] for line in needed.splitlines() if "NEEDED" in line}
    assert libraries <= {"libc.so.6", "libm.so.6"}
