"""Plots of results: planar traction maps (matplotlib, off-screen).

``plot_result`` draws, for every patch with a traction field, three maps: the pressure p_n, the
tangential traction |p_t| with its direction, and the element status (exterior / adhesion / slip).
Results without a field (Hertz, linear, empirical) are drawn as their Hertz ellipse pressure.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from conformal.result import ADHESION, SLIP, Result


def _figure(rows: int, cols: int, size: float = 3.6):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, cols, figsize=(cols * size + 0.8, rows * size), squeeze=False)
    return plt, fig, axes


def _edges(grid):
    return (grid.xl + np.arange(grid.mx + 1) * grid.dx, grid.yl + np.arange(grid.my + 1) * grid.dy)


def _draw_field(fig, axes, result: Result, label: str) -> None:
    f = result.field
    xe, ye = _edges(f.grid)
    ax = axes[0]
    m = ax.pcolormesh(xe, ye, f.pn.T, cmap="viridis", shading="flat")
    fig.colorbar(m, ax=ax, label="p_n [N/mm²]")
    ax.set_title(f"{label} pressure, pmax {result.pmax:.4g}")
    ax = axes[1]
    pt = np.hypot(f.px, f.py)
    m = ax.pcolormesh(xe, ye, pt.T, cmap="magma", shading="flat")
    fig.colorbar(m, ax=ax, label="|p_t| [N/mm²]")
    step = max(1, max(f.grid.mx, f.grid.my) // 20)
    X, Y = f.grid.mesh()
    sel = (slice(None, None, step), slice(None, None, step))
    mask = pt[sel] > 0
    if mask.any():
        ax.quiver(X[sel][mask], Y[sel][mask], f.px[sel][mask], f.py[sel][mask], color="white", pivot="mid")
    ax.set_title(f"traction, FX {result.FX:.4g} FY {result.FY:.4g}")
    ax = axes[2]
    code = np.zeros(f.status.shape)
    code[f.status == ADHESION] = 1
    code[f.status == SLIP] = 2
    from matplotlib.colors import ListedColormap

    ax.pcolormesh(xe, ye, code.T, cmap=ListedColormap(["#dddddd", "#2b83ba", "#d7191c"]), vmin=0, vmax=2,
                  shading="flat")
    ax.set_title(f"adhesion (blue) {f.n_adhesion}, slip (red) {f.n_slip}")
    for a in axes:
        a.set_aspect("equal")
        a.set_xlabel("x (rolling) [mm]")
        a.set_ylabel("y [mm]")


def _draw_ellipse(fig, ax, result: Result, label: str) -> None:
    a, b = result.a, result.b
    x = np.linspace(-1.2 * a, 1.2 * a, 121)
    y = np.linspace(-1.2 * b, 1.2 * b, 121)
    X, Y = np.meshgrid(x, y, indexing="ij")
    p = result.pmax * np.sqrt(np.clip(1 - (X / a) ** 2 - (Y / b) ** 2, 0, None))
    m = ax.pcolormesh(x, y, p.T, cmap="viridis", shading="auto")
    fig.colorbar(m, ax=ax, label="p_n [N/mm²]")
    ax.set_aspect("equal")
    ax.set_title(f"{label} ({result.theory}): Hertz pressure, FX {result.FX:.4g} FY {result.FY:.4g}")
    ax.set_xlabel("x (rolling) [mm]")
    ax.set_ylabel("y [mm]")


def plot_result(result: Result, path: str | Path, title: str | None = None) -> Path:
    """Write a PNG of the result's traction maps (one row per contact patch)."""
    parts = list(result.patches) or [result]
    plt, fig, axes = _figure(len(parts), 3)
    for row, part in enumerate(parts):
        label = str(part.extra.get("label", f"patch {row + 1}")) if len(parts) > 1 else "contact"
        if part.field is not None:
            _draw_field(fig, axes[row], part, label)
        else:
            _draw_ellipse(fig, axes[row][0], part, label)
            axes[row][1].axis("off")
            axes[row][2].axis("off")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ----------------------------------------------------------------------------- 3-D (pyvista, meshio)
def strip_points(x_edges: np.ndarray, y_edges: np.ndarray, z_edges: np.ndarray) -> np.ndarray:
    """Corner points (mx+1, ms+1, 3) of a strip: x along rolling, (y, z) the profile edges along s."""
    nx, ns = len(x_edges), len(y_edges)
    P = np.empty((nx, ns, 3))
    P[..., 0] = np.asarray(x_edges)[:, None]
    P[..., 1] = np.asarray(y_edges)[None, :]
    P[..., 2] = np.asarray(z_edges)[None, :]
    return P


def strip_mesh(points: np.ndarray, cell_data: dict[str, np.ndarray] | None = None):
    """A pyvista StructuredGrid of quadrilateral cells from corner points (nx, ns, 3);
    ``cell_data`` arrays have shape (nx-1, ns-1) or (nx-1, ns-1, 3)."""
    import pyvista as pv

    nx, ns = points.shape[:2]
    grid = pv.StructuredGrid()
    grid.points = points.transpose(1, 0, 2).reshape(-1, 3)  # x fastest (VTK order)
    grid.dimensions = (nx, ns, 1)
    for name, values in (cell_data or {}).items():
        v = np.asarray(values, dtype=float)
        grid.cell_data[name] = v.transpose(1, 0, *range(2, v.ndim)).reshape((nx - 1) * (ns - 1), *v.shape[2:])
    return grid


def export_vtu(path: str | Path, points: np.ndarray, cell_data: dict[str, np.ndarray]) -> Path:
    """Write a strip of quadrilaterals with per-element data as VTU (meshio), for ParaView."""
    import meshio

    nx, ns = points.shape[:2]
    idx = np.arange(nx * ns).reshape(nx, ns)
    quads = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1).reshape(-1, 4)
    data = {k: [np.asarray(v, dtype=float).reshape((nx - 1) * (ns - 1), *np.shape(v)[2:])]
            for k, v in cell_data.items()}
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, meshio.Mesh(points.reshape(-1, 3), [("quad", quads)], cell_data=data))
    return path


def plot_surfaces_3d(path: str | Path, contact: "object", *, bodies: list | None = None,
                     scalar: str = "pn", vectors: np.ndarray | None = None, boundary: "object" = None,
                     title: str = "", window: tuple[int, int] = (1200, 900)) -> Path:
    """Off-screen pyvista PNG: body surfaces (grey, translucent), the contact strip coloured by
    ``scalar``, traction vectors (glyphs at element centres) and a slip/adhesion boundary line.

    ``contact`` is a StructuredGrid from :func:`strip_mesh`; ``bodies`` more meshes to show;
    ``vectors`` (mx*ms, 3) traction vectors at cell centres in 3-D; ``boundary`` a PolyData line.
    """
    import pyvista as pv

    pv.OFF_SCREEN = True
    plotter = pv.Plotter(off_screen=True, window_size=list(window))
    for body in bodies or []:
        plotter.add_mesh(body, color="lightgrey", opacity=0.35, show_edges=False)
    plotter.add_mesh(contact, scalars=scalar, cmap="viridis", show_edges=True, edge_color="#555555",
                     scalar_bar_args={"title": scalar})
    if vectors is not None:
        centres = contact.cell_centers()
        centres["traction"] = np.asarray(vectors)
        scale = 0.3 * max(contact.length / 10, 1e-9) / max(np.abs(vectors).max(), 1e-300)
        plotter.add_mesh(centres.glyph(orient="traction", scale="traction", factor=scale), color="white")
    if boundary is not None:
        plotter.add_mesh(boundary, color="red", line_width=4)
    if title:
        plotter.add_text(title, font_size=10)
    plotter.view_isometric()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    plotter.screenshot(str(path))
    plotter.close()
    return path
