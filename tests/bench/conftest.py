"""Put bench/ on sys.path so that the tests import the benchmark helpers as ``realdata``
(bench/ is a folder of scripts, not an installed package)."""
from __future__ import annotations

import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "bench"
if str(BENCH) not in sys.path:
    sys.path.insert(0, str(BENCH))
