"""Packaging and validation of the FMUs built by build.sh.

    python -m harness.package BUILD_DIR OUT.fmu    zip an FMU directory
    python -m harness.package --validate A.fmu ... check with fmpy's validator
"""
from __future__ import annotations

import sys
import zipfile
from pathlib import Path


def zip_fmu(directory: Path, fmu: Path) -> None:
    """Zip an extracted FMU layout (modelDescription.xml, binaries/, sources/) into ``fmu``."""
    directory, fmu = Path(directory), Path(fmu)
    fmu.parent.mkdir(parents=True, exist_ok=True)
    members = [directory / "modelDescription.xml"]
    for folder in ("binaries", "sources", "documentation", "resources"):
        members += sorted(p for p in (directory / folder).rglob("*") if p.is_file())
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in members:
            archive.write(path, path.relative_to(directory).as_posix())


def validate(fmus: list[Path]) -> int:
    """Run ``fmpy.validation.validate_fmu`` on each FMU; print problems; return their count."""
    from fmpy.validation import validate_fmu

    count = 0
    for fmu in fmus:
        problems = validate_fmu(str(fmu))
        for problem in problems:
            print(f"{fmu}: {problem}", file=sys.stderr)
        count += len(problems)
        print(f"{fmu}: {'valid' if not problems else f'{len(problems)} problem(s)'}")
    return count


def main(argv: list[str]) -> int:
    if argv and argv[0] == "--validate":
        return 1 if validate([Path(a) for a in argv[1:]]) else 0
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    zip_fmu(Path(argv[0]), Path(argv[1]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
