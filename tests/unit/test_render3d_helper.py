"""The demo's 3-D view drawn by a helper process (conformal.plots.Render3D, issue 13: the pyvista
import and window open while the solve runs) is the picture drawn in this process."""

import numpy as np
import pytest

from conformal.plots import Render3D, render_conformal_3d
from conformal.scene import load_scene
from conformal.dispatch import solve_scene
from _paths import SCENES



@pytest.mark.slow
def test_helper_process_draws_the_same_picture():
    render = Render3D((320, 240))            # started before the solve, as in `conformal demo`
    sc = load_scene(SCENES / "flange_s1002_uic60.toml")
    r = solve_scene(sc.with_("grid.n", 12))
    render.send(r)
    img = render.image()
    here = render_conformal_3d(r, window=(320, 240))
    assert img.shape == here.shape == (240, 320, 3)
    # the same scene drawn by the same VTK: identical up to a few pixels of rasterisation
    differ = np.any(img != here, axis=-1).mean()
    assert differ < 0.01
    # the view is not empty: the viridis pressure colours cover part of it
    assert np.any(img != img[0, 0], axis=-1).mean() > 0.1


def test_helper_released_without_a_result():
    render = Render3D((64, 48))
    render.close()                           # e.g. the solve failed: the helper must not linger
    render.close()
    assert render._proc is None and render._conn is None
