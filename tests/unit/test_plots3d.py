"""3-D output of conformal results: the pyvista off-screen view, the PNG of `conformal solve --plot`,
and the VTU files for ParaView (read back with meshio and checked against the result)."""

import meshio
import numpy as np
import pytest

from conformal.cli import main
from conformal.plots import curved_strip_points, export_conformal_vtu, render_conformal_3d
from conformal.scene import load_scene
from conformal.dispatch import solve_scene
from _paths import SCENES



@pytest.fixture(scope="module")
def flange_result():
    sc = load_scene(SCENES / "flange_s1002_uic60.toml")
    return solve_scene(sc.with_("grid.n", 12))


def _quad_areas(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    p = points[quads]
    return 0.5 * np.linalg.norm(np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]), axis=1)


def test_vtu_holds_the_tractions_on_the_curved_surface(flange_result, tmp_path):
    """Read back: one quad per element on the rail surface; sum pn dS over the quads is FN (0.5 %:
    flat quads on the curved profile); the cell with the largest pressure sits where the result's
    largest pressure is (same element in 3-D); the traction vectors are tangent to the surface and
    their sum is (FX, FS) in the element frames; rail and wheel surfaces written next to it."""
    r = flange_result
    paths = export_conformal_vtu(r, tmp_path / "flange.vtu")
    assert [p.name for p in paths] == ["flange.vtu", "flange_rail.vtu", "flange_wheel.vtu"]
    m = meshio.read(paths[0])
    quads = m.cells_dict["quad"]
    g = r.field.curved
    assert len(quads) == g.size
    pn = m.cell_data["pn"][0]
    dS = _quad_areas(m.points, quads)
    assert float((pn * dS).sum()) == pytest.approx(r.FN, rel=5e-3)
    k = int(np.argmax(pn))
    centre = m.points[quads[k]].mean(axis=0)
    ix, js = np.unravel_index(int(np.argmax(r.field.side_frame("pn"))), g.shape)
    P = curved_strip_points(g)
    np.testing.assert_allclose(centre, P[ix:ix + 2, js:js + 2].reshape(-1, 3).mean(axis=0), atol=1e-9)
    T = m.cell_data["traction"][0]
    normals = np.cross(m.points[quads[:, 2]] - m.points[quads[:, 0]], m.points[quads[:, 3]] - m.points[quads[:, 1]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    assert np.abs(np.einsum("ij,ij->i", T, normals)).max() < 0.02 * np.abs(T).max()   # tangent (chords)
    assert float((m.cell_data["px"][0] * dS).sum()) == pytest.approx(r.FX, rel=5e-3)
    np.testing.assert_array_equal(m.cell_data["status"][0].reshape(g.shape), r.field.side_frame("status"))
    for p in paths[1:]:
        assert len(meshio.read(p).cells_dict["quad"]) > 100


def test_render_shows_the_pressure(flange_result):
    """The off-screen view holds the colours of the pressure scale (viridis: the peak is yellow)
    and changes when another quantity colours the strip."""
    a = render_conformal_3d(flange_result, window=(500, 400))
    b = render_conformal_3d(flange_result, scalar="pt", window=(500, 400))
    assert a.shape == (400, 500, 3)
    yellow = (a[..., 0] > 200) & (a[..., 1] > 180) & (a[..., 2] < 110)
    assert yellow.sum() > 50                       # measured 666 pixels
    assert np.abs(a.astype(int) - b).sum() > 1e4


@pytest.mark.slow
def test_cli_solve_plot_and_vtu(tmp_path, capsys):
    """`conformal solve --plot --vtu` on a conformal scene writes the PNG (3-D view and developed
    maps) and the VTU files; --vtu with a planar theory is refused with one line (exit 2)."""
    scene = tmp_path / "flange.toml"
    scene.write_text((SCENES / "flange_s1002_uic60.toml").read_text().replace("n = 40", "n = 10"))
    png, vtu = tmp_path / "f.png", tmp_path / "f.vtu"
    assert main(["solve", str(scene), "--plot", str(png), "--vtu", str(vtu)]) == 0
    assert png.stat().st_size > 50_000 and vtu.is_file() and (tmp_path / "f_wheel.vtu").is_file()
    capsys.readouterr()
    assert main(["solve", str(scene), "--theory", "fastsim", "--vtu", str(vtu)]) == 2
    assert "--vtu: needs [model] theory = \"conformal\"" in capsys.readouterr().err
