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
