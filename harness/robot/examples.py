"""The robots that the pinned PyPI package example-robot-data ships, by short name."""
from __future__ import annotations

from importlib.metadata import PackageNotFoundError, files
from pathlib import Path

# short name -> (URDF file name, joints to lock so that a serial arm remains)
EXAMPLES = {
    "ur5": ("ur5_robot.urdf", ()),
    "panda": ("panda.urdf", ("panda_finger_joint1", "panda_finger_joint2")),
    "double_pendulum": ("double_pendulum.urdf", ()),
}


def example_urdf(name: str) -> tuple[Path, tuple[str, ...]]:
    """(URDF path, joints to lock) of an example robot; ValueError if unknown or missing."""
    if name not in EXAMPLES:
        raise ValueError(f"unknown example robot {name!r} (known: {', '.join(EXAMPLES)})")
    file_name, locked = EXAMPLES[name]
    try:
        shipped = files("example-robot-data") or []
    except PackageNotFoundError:
        raise ValueError("the example robots need the package example-robot-data "
                         "(pip install -r requirements.txt)") from None
    for entry in shipped:
        if entry.name == file_name and "/urdf/" in str(entry):
            return Path(entry.locate()), locked
    raise ValueError(f"example-robot-data does not ship {file_name}")
