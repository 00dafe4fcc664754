"""harness.paths: the FMUs' folder when none is given ($STO_FMU_DIR, a checkout's build,
else the package's own copy)."""
from __future__ import annotations

from harness import paths


def test_the_environment_names_the_folder_first(monkeypatch, tmp_path):
    monkeypatch.setenv("STO_FMU_DIR", str(tmp_path))
    assert paths.default_fmu_dir() == tmp_path


def test_a_checkout_build_comes_before_the_packaged_copy(monkeypatch, tmp_path):
    monkeypatch.delenv("STO_FMU_DIR", raising=False)
    monkeypatch.setattr(paths, "CHECKOUT_FMUS", tmp_path / "build")
    assert paths.default_fmu_dir() == paths.PACKAGED_FMUS  # no build there
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / paths.OBSERVER).write_bytes(b"")
    assert paths.default_fmu_dir() == tmp_path / "build"
