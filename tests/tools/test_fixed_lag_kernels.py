"""The fixed-lag window's generated kernel table is the one tools/fixed_lag_kernels.py
designs from tuning.h: a change of the tuning without regenerating it fails here."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_the_kernel_header_is_up_to_date():
    run = subprocess.run([sys.executable, "-m", "tools.fixed_lag_kernels", "--check"],
                         cwd=REPO, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "up to date" in run.stdout
