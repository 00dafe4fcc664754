"""The shared libraries export the FMI 2.0 (FMI 3.0) functions and nothing else, and need only
libc/libm."""
from __future__ import annotations

import subprocess
import zipfile

import pytest

from tests.conftest import MODEL_IDENTIFIERS

COMMON = """GetTypesPlatform GetVersion SetDebugLogging Instantiate FreeInstance SetupExperiment
EnterInitializationMode ExitInitializationMode Terminate Reset GetReal GetInteger GetBoolean
GetString SetReal SetInteger SetBoolean SetString GetFMUstate SetFMUstate FreeFMUstate
SerializedFMUstateSize SerializeFMUstate DeSerializeFMUstate GetDirectionalDerivative""".split()
COSIMULATION = """SetRealInputDerivatives GetRealOutputDerivatives DoStep CancelStep GetStatus
GetRealStatus GetIntegerStatus GetBooleanStatus GetStringStatus""".split()


def _exports(fmu, member: str, library):
    """The symbols the FMU's binary ``member`` exports (copied to ``library``)."""
    library.write_bytes(zipfile.ZipFile(fmu).read(member))
    symbols = subprocess.run(["nm", "-D", "--defined-only", str(library)], capture_output=True,
                             text=True, check=True).stdout.split("\n")
    return {line.split()[-1] for line in symbols if line.strip()}


@pytest.mark.parametrize("model", MODEL_IDENTIFIERS)
def test_exports_and_dependencies(tmp_path, observer_fmu, model):
    library = tmp_path / f"{model}.so"
    exported = _exports(observer_fmu.parent / f"{model}.fmu", f"binaries/linux64/{model}.so",
                        library)
    assert exported == {f"fmi2{name}" for name in COMMON + COSIMULATION}
    needed = subprocess.run(["objdump", "-p", str(library)], capture_output=True, text=True,
                            check=True).stdout
    libraries = {line.split()[-1] for line in needed.splitlines() if "NEEDED" in line}
    assert libraries <= {"libc.so.6", "libm.so.6"}


def _fmi3_functions() -> set[str]:
    """Every function fmpy's fmi3Functions.h declares."""
    import re
    from pathlib import Path

    import fmpy

    header = (Path(fmpy.__file__).parent / "c-code" / "fmi3Functions.h").read_text()
    return set(re.findall(r"FMI3_Export\s+fmi3\w+TYPE\s+(fmi3\w+)\s*;", header))


@pytest.mark.parametrize("model", MODEL_IDENTIFIERS)
def test_fmi3_exports_every_fmi3_function_and_nothing_else(tmp_path, observer_fmi3, model):
    exported = _exports(observer_fmi3.parent / f"{model}.fmu",
                        f"binaries/x86_64-linux/{model}.so", tmp_path / f"{model}.so")
    expected = _fmi3_functions()
    assert len(expected) > 60 and exported == expected
