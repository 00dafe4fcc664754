"""harness.plots: the identification figure drawn from an estimates table (only the
coefficients that were identified, nominal values marked) and written as a PNG."""
from __future__ import annotations

import numpy as np
from PIL import Image

from harness.plots import plot_identification


def test_the_identification_figure_is_written(tmp_path):
    t = np.linspace(0.0, 10.0, 2001)
    columns = {"x2_hat": np.cos(t), "z_eq_filtered": 0.1 * np.sin(40 * t),
               "b_hat": np.full_like(t, 2.0), "b_std": np.full_like(t, 0.1),
               "theta_hat[1,1]": 1 - np.exp(-t), "theta_std[1,1]": 0.1 * np.exp(-t),
               "theta_hat[1,2]": np.zeros_like(t), "theta_std[1,2]": np.zeros_like(t)}
    path = plot_identification(t, columns, tmp_path, nominal={"c_nominal[1]": 0.9, "b": 2.2})
    assert path == tmp_path / "identification.png"
    with Image.open(path) as image:
        width, height = image.size
        colours = len(np.unique(np.asarray(image.convert("RGB")).reshape(-1, 3), axis=0))
    assert width > 500 and height > 700 and colours > 20  # drawn, not blank
