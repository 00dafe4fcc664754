"""Where the harness finds its FMUs, in a source checkout and when installed."""
from __future__ import annotations

import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
CHECKOUT_FMUS = PACKAGE.parent / "build" / "fmus"  # ./build.sh fmus writes them here
PACKAGED_FMUS = PACKAGE / "data"  # the copy a wheel ships (./build.sh puts it there)
OBSERVER = "SuperTwistingObserver.fmu"


def default_fmu_dir() -> Path:
    """The folder of the FMUs when none is given: ``$STO_FMU_DIR`` if set, else
    the freshly built ``build/fmus`` of a source checkout, else the FMUs installed
    with the package."""
    if os.environ.get("STO_FMU_DIR"):
        return Path(os.environ["STO_FMU_DIR"])
    if (CHECKOUT_FMUS / OBSERVER).exists():
        return CHECKOUT_FMUS
    return PACKAGED_FMUS
