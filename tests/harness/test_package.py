"""harness.package: an FMU layout zipped with its members at their FMI places, and
fmpy's validator run over FMUs (its problems counted)."""
from __future__ import annotations

import zipfile

from harness.package import main, validate, zip_fmu
from harness.paths import OBSERVER, default_fmu_dir


def test_a_layout_is_zipped_with_posix_member_names(tmp_path):
    layout = tmp_path / "layout"
    (layout / "binaries" / "linux64").mkdir(parents=True)
    (layout / "sources" / "core").mkdir(parents=True)
    (layout / "modelDescription.xml").write_text("<fmiModelDescription/>")
    (layout / "binaries" / "linux64" / "M.so").write_bytes(b"\x7fELF")
    (layout / "sources" / "core" / "a.c").write_text("int a;")
    (layout / "notes.txt").write_text("not part of an FMU")
    zip_fmu(layout, tmp_path / "out" / "M.fmu")
    with zipfile.ZipFile(tmp_path / "out" / "M.fmu") as archive:
        assert archive.namelist() == ["modelDescription.xml", "binaries/linux64/M.so",
                                      "sources/core/a.c"]


def test_the_built_observer_validates_and_a_broken_fmu_does_not(tmp_path, capsys):
    assert validate([default_fmu_dir() / OBSERVER]) == 0
    broken = tmp_path / "broken.fmu"
    with zipfile.ZipFile(broken, "w") as archive:
        archive.writestr("modelDescription.xml", "<fmiModelDescription/>")
    assert main(["--validate", str(broken)]) == 1
    assert "broken.fmu" in capsys.readouterr().err
