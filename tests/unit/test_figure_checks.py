"""Issue 22 item 12: what the figures say (checked on the matplotlib/pyvista objects; the PNGs
were also looked at, see docs/validation/reliability.md)."""
from __future__ import annotations


import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

import conformal
from conformal.dynamics.plots import SEED_CRITICAL_SPEED, damping_figure, history_figures
from conformal.plots import force_text, plot_pressure
from _paths import SCENES


def _legend(fig) -> list[str]:
    leg = fig.axes[0].get_legend()
    return [t.get_text() for t in leg.get_texts()] if leg is not None else []


def test_stability_figure_draws_the_vehicles_critical_speed_not_the_seeds():
    v = np.linspace(1.0, 100.0, 50)
    fig = damping_figure(v, 0.1 - v / 500.0, np.ones_like(v), critical=50.0)
    labels = _legend(fig)
    assert labels == ["linear critical: 50.0 m/s"]            # no 69 m/s line of the seed's vehicle
    lines = [ln.get_xdata()[0] for ln in fig.axes[0].get_lines()[2:]]
    assert lines == [50.0]
    seed = _legend(damping_figure(v, 0.1 - v / 500.0, np.ones_like(v), critical=50.0,
                                  reference=SEED_CRITICAL_SPEED))
    assert any("seed" in t and "69.0" in t for t in seed)
    assert _legend(damping_figure(v, 0.1 + 0 * v, np.ones_like(v))) == []   # no hunting: no line


def test_spin_panel_is_in_the_csv_unit():
    t = np.linspace(0.0, 1.0, 11)
    h = {"t": t, "y": t, "right_xi": t, "right_eta": t, "right_phi": 1e-4 * t, "right_a": t, "right_b": t,
         "right_FZ": t, "right_FX": t, "right_FY": t}
    ax = history_figures(h)["fig12_creepages.png"].axes[2]
    assert "rad/mm" in ax.get_ylabel()
    np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), h["right_phi"])


def test_round_off_is_printed_as_zero_and_line_contact_in_n_per_mm():
    assert force_text(3.752e-06, 1e4) == "0" and force_text(-14231.4, 1e5) == "-14231"
    assert force_text(-142.71, 1.16e4) == "-142.7" and force_text(0.5, 1e4) == "0.5"
    r = conformal.solve(SCENES / "circ.toml", model__theory="exact", grid__n=16)
    assert 0 < abs(r.FY) < 1e-7 * r.FN                    # round-off of the solver
    title = plot_pressure(r, Figure().subplots(), quantity="pt").get_title()
    assert "FS 0 N" in title and "e-0" not in title
    line = conformal.solve(SCENES / "line_carter.toml", grid__n=40)
    title = plot_pressure(line, Figure().subplots(), quantity="pt").get_title()
    assert "N/mm" in title and title.count("N/mm") == 2


def test_tick_labels_of_a_narrow_map_do_not_overlap():
    """An elongated contact (b/a about 10) drawn as a stretched narrow map: the labels of either
    axis must not overlap each other."""
    r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-5}, "load": {"normal_force": 1e4},
                         "kinematics": {"xi": 1e-3}, "grid": {"n": 20}, "model": {"theory": "fastsim"}})
    from conformal.plots import _draw_field, _figure

    _, fig, axes = _figure(1, 3)                  # as plot_result draws a patch's row
    FigureCanvasAgg(fig)
    _draw_field(fig, axes[0], r, "")
    fig.tight_layout()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes[:3]:
        for axis in (ax.xaxis, ax.yaxis):
            boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels() if t.get_text()]
            for b0, b1 in zip(boxes, boxes[1:]):
                assert not b0.overlaps(b1), (ax.get_title(), [t.get_text() for t in axis.get_ticklabels()])


@pytest.mark.slow
def test_3d_view_has_orientation_scale_and_a_readable_number_of_arrows():
    """The 3-D view of a conformal result (the flange patch, 30 elements per axis: 13 s): the axes
    triad, a horizontal colour bar, the ruler's label and 0.25-1.5 x ARROWS_3D arrows."""
    pv = pytest.importorskip("pyvista")
    from conformal.plots import ARROWS_3D, _offscreen_plotter, plot3d
    from conformal.scene import load_scene

    sc = load_scene(SCENES / "flange_s1002_uic60.toml")
    r = conformal.solve(sc.with_("grid.n", 30))
    pl = _offscreen_plotter((400, 300))
    plot3d(r, pl)
    assert pl.renderer.axes_widget is not None                       # the x, y, z triad
    bars = list(pl.scalar_bars.values())
    assert bars and bars[0].GetOrientation() == 0                    # horizontal, below the view
    assert bars[0].GetNumberOfLabels() == 2                           # 0 and the maximum: clear of the title
    texts = [a.GetInput() for a in pl.renderer.actors.values() if hasattr(a, "GetInput")
             and isinstance(a.GetInput(), str)]
    assert any("x rolling (red)" in t for t in texts)                # the triad's legend (no colliding labels)
    assert any(name.endswith("-labels") for name in pl.renderer.actors)   # the ruler's "N mm" label
    n_contact = r.n_contact
    arrows = [m for m in pl.meshes if getattr(m, "n_points", 0) and m.n_cells and "GlyphScale" in m.point_data]
    assert n_contact > ARROWS_3D and arrows
    n_arrows = arrows[0].n_cells / pv.Arrow(tip_length=0.4, tip_radius=0.2, shaft_radius=0.07).n_cells
    assert 0.25 * ARROWS_3D <= n_arrows <= 1.5 * ARROWS_3D
    pl.close()
