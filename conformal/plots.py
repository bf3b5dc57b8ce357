"""Plots of results: planar traction maps (matplotlib) and 3-D views (pyvista).

``plot_result`` writes a file: for every patch with a traction field three maps (the pressure
p_n, the tangential traction |p_t| with its direction, the element status exterior / adhesion /
slip); results without a field (Hertz, linear, empirical) are drawn as their Hertz ellipse
pressure.  :func:`plot_pressure` draws one map into a given matplotlib Axes (``Result.plot``) and
:func:`plot3d` adds a result to a given pyvista Plotter (``Result.plot3d``).

Library code changes no global state: no matplotlib backend is selected (figures are
``matplotlib.figure.Figure`` objects written directly), and pyvista plotters are created
off-screen per call (never ``pyvista.OFF_SCREEN``).  Where no X display exists the render window
is EGL, so VTK does not warn about a missing X server.

Names: the contact-frame tangential forces are FX (rolling) and FS (lateral, in the contact plane;
``FY`` in the JSON); the track-frame lateral force on the rail is FY_track.

This module imports nothing from the rest of the package (results are read by their attributes),
so that :class:`conformal.result.Result` can draw itself.
"""
from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np

from conformal.files import atomic_path, save_figure

# the element status flags of conformal.result.TractionField (tests/unit/test_plots3d.py checks they agree)
EXTERIOR, ADHESION, SLIP = 0, 1, 2


def _figure(rows: int, cols: int, size: float = 3.6):
    """A matplotlib Figure (not registered with pyplot: no backend switch, nothing global)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(cols * size + 0.8, rows * size))
    axes = np.atleast_2d(fig.subplots(rows, cols, squeeze=False))
    return None, fig, axes


def _edges(grid):
    return (grid.xl + np.arange(grid.mx + 1) * grid.dx, grid.yl + np.arange(grid.my + 1) * grid.dy)


#: a map is drawn to scale up to this ratio of its sides; a thinner one is drawn with this ratio
#: (the short side stretched, and the axis label says by how much)
MAX_MAP_RATIO = 3.0


def _aspect(ax, width: float, height: float) -> None:
    """Equal axes unless the patch is thin, where the long side would squeeze the short one to a
    line: then the panel keeps the sides MAX_MAP_RATIO : 1 and the label of the stretched axis
    says so; at most 5 ticks per axis (no overlapping labels)."""
    from matplotlib.ticker import MaxNLocator

    ratio = max(width, height) / max(min(width, height), 1e-12)
    wide = width >= height
    if ratio <= MAX_MAP_RATIO:
        ax.set_aspect("equal", adjustable="box")
    else:
        stretch = ratio / MAX_MAP_RATIO
        ax.set_aspect(stretch if wide else 1.0 / stretch, adjustable="box")
        axis = ax.yaxis if wide else ax.xaxis
        axis.set_label_text(f"{axis.get_label_text()} (stretched {stretch:.1f}x)")
    # the short side is drawn 1/min(ratio, MAX_MAP_RATIO) as long: fewer ticks there, so that its
    # labels do not run into each other on a narrow map
    short = max(3, int(round(5.0 / min(ratio, MAX_MAP_RATIO))))
    ax.xaxis.set_major_locator(MaxNLocator(5 if wide else short))
    ax.yaxis.set_major_locator(MaxNLocator(short if wide else 5))


def force_text(value: float, scale: float, digits: int = 4) -> str:
    """A force (or moment) for a title: ``digits`` significant digits, and 0 where it is round-off,
    below ROUND_OFF times ``scale`` (the largest force of the result, e.g. FN).

    >>> force_text(3.752e-06, 1e4), force_text(-3426.4, 1.16e4), force_text(-142.71, 1.16e4)
    ('0', '-3426', '-142.7')
    """
    if not abs(value) > ROUND_OFF * abs(scale):
        return "0"
    whole = int(np.floor(np.log10(abs(value)))) + 1       # no exponent for whole newtons (-14230)
    return f"{value:.{max(digits, whole)}g}"


#: a force below this fraction of the result's largest force is round-off of the solver (its
#: tolerance is 1e-6 and below) and is printed as 0
ROUND_OFF = 1e-7


def _force_unit(result) -> str:
    """N, or N/mm for line contact (forces per mm of line length)."""
    return "N/mm" if result.extra.get("line_contact") else "N"


def _forces_title(result, names=(("FX", "FX"), ("FS", "FY"))) -> str:
    """'FX -3426 N, FS 0 N' with the round-off shown as 0 and line contact in N/mm."""
    scale = max(abs(result.FN), abs(result.FX), abs(result.FY))
    unit = _force_unit(result)
    return ", ".join(f"{label} {force_text(getattr(result, attr), scale)} {unit}" for label, attr in names)


def _colorbar(fig, mappable, ax, label: str) -> None:
    """A colour bar as tall as the map itself (an inset beside it, so that it follows the map's
    aspect), at most 4 labelled ticks."""
    cb = fig.colorbar(mappable, cax=ax.inset_axes([1.04, 0.0, 0.05, 1.0]), label=label)
    from matplotlib.ticker import MaxNLocator

    cb.locator = MaxNLocator(4)
    cb.update_ticks()


def _draw_map(fig, ax, result, quantity: str = "pn", label: str = "") -> None:
    """One map of a planar (or developed) traction field: ``quantity`` "pn", "pt" or "status"."""
    f = result.field
    xe, ye = _edges(f.grid)
    if quantity == "pn":
        v = f.pn
        m = ax.pcolormesh(xe, ye, v.T, cmap="viridis", shading="flat", vmin=0.0, vmax=max(float(v.max()), 1e-12))
        _colorbar(fig, m, ax, "p_n [N/mm²]")
        ax.set_title(f"{label}pressure p_n, pmax {result.pmax:.4g} N/mm²".strip(), fontsize=9)
    elif quantity == "pt":
        pt = np.hypot(f.px, f.py)
        m = ax.pcolormesh(xe, ye, pt.T, cmap="magma", shading="flat", vmin=0.0, vmax=max(float(pt.max()), 1e-12))
        _colorbar(fig, m, ax, "|p_t| [N/mm²]")
        step = max(1, max(f.grid.mx, f.grid.my) // 20)
        X, Y = f.grid.mesh()
        sel = (slice(None, None, step), slice(None, None, step))
        mask = pt[sel] > 0
        if mask.any():
            ax.quiver(X[sel][mask], Y[sel][mask], f.px[sel][mask], f.py[sel][mask], color="white", pivot="mid")
        ax.set_title(f"{label}traction, {_forces_title(result)}".strip(), fontsize=9)
    elif quantity == "status":
        from matplotlib.colors import ListedColormap

        code = np.zeros(f.status.shape)
        code[f.status == ADHESION] = 1
        code[f.status == SLIP] = 2
        ax.pcolormesh(xe, ye, code.T, cmap=ListedColormap(["#dddddd", "#2b83ba", "#d7191c"]), vmin=0, vmax=2,
                      shading="flat")
        ax.set_title(f"{label}adhesion (blue) {f.n_adhesion}, slip (red) {f.n_slip} elements".strip(), fontsize=9)
    else:
        raise ValueError(f"quantity: one of 'pn', 'pt', 'status', got {quantity!r}")
    ax.set_xlabel("x (rolling) [mm]")
    ax.set_ylabel("y [mm]")
    _aspect(ax, xe[-1] - xe[0], ye[-1] - ye[0])


def _draw_field(fig, axes, result, label: str) -> None:
    for ax, q in zip(axes, ("pn", "pt", "status")):
        _draw_map(fig, ax, result, q, label=f"{label}: " if label else "")


def _draw_ellipse(fig, ax, result, label: str) -> None:
    a, b = result.a, result.b
    x = np.linspace(-1.2 * a, 1.2 * a, 121)
    y = np.linspace(-1.2 * b, 1.2 * b, 121)
    X, Y = np.meshgrid(x, y, indexing="ij")
    p = result.pmax * np.sqrt(np.clip(1 - (X / a) ** 2 - (Y / b) ** 2, 0, None))
    m = ax.pcolormesh(x, y, p.T, cmap="viridis", shading="auto", vmin=0.0)
    _colorbar(fig, m, ax, "p_n [N/mm²]")
    ax.set_title(f"{label} ({result.theory}): Hertz pressure, pmax {result.pmax:.4g} N/mm²\n"
                 f"{_forces_title(result)}", fontsize=9)
    ax.set_xlabel("x (rolling) [mm]")
    ax.set_ylabel("y [mm]")
    _aspect(ax, 2.4 * a, 2.4 * b)


def plot_pressure(result, ax=None, quantity: str = "pn", patch: int | None = None):
    """Draw one map of a result into a matplotlib Axes and return the Axes.

    Parameters
    ----------
    result : conformal.result.Result
        Any model's result.  A result without a traction field (Hertz, linear, empirical) is drawn
        as its Hertz pressure ellipse.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure (``matplotlib.pyplot.subplots``) when omitted.
    quantity : {"pn", "pt", "status"}
        Pressure, tangential traction (with arrows) or adhesion/slip.
    patch : int, optional
        Which contact patch of a multi-patch result (default: the most loaded one).

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> from matplotlib.figure import Figure
    >>> import conformal
    >>> r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
    ...                      "load": {"normal_force": 1e4}, "model": {"theory": "hertz"}})
    >>> ax = plot_pressure(r, Figure().subplots())
    >>> ax.get_xlabel()
    'x (rolling) [mm]'
    """
    part = result
    if result.field is None and result.patches:
        parts = list(result.patches)
        part = parts[patch] if patch is not None else max(parts, key=lambda r: r.FN)
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    fig = ax.figure
    if part.field is not None:
        _draw_map(fig, ax, part, quantity)
    else:
        _draw_ellipse(fig, ax, part, "contact")
    return ax


def plot_result(result, path: str | Path, title: str | None = None, *, render: "Render3D | None" = None) -> Path:
    """Write an image of the result's traction maps (one row per contact patch); a conformal result
    (curved grid) gets :func:`plot_conformal_result` (3-D view and developed maps).  The file
    type follows the suffix of ``path`` (png, pdf, svg, ...).  ``render``: a :class:`Render3D`
    started earlier draws the 3-D view (closed here in any case)."""
    if _curved_field(result) is not None:
        return plot_conformal_result(result, path, title, render=render)
    if render is not None:
        render.close()
    parts = list(result.patches) or [result]
    _, fig, axes = _figure(len(parts), 3)
    for row, part in enumerate(parts):
        label = str(part.extra.get("label", f"patch {row + 1}")) if len(parts) > 1 else ""
        if part.field is not None:
            _draw_field(fig, axes[row], part, label)
        else:
            _draw_ellipse(fig, axes[row][0], part, label or "contact")
            axes[row][1].axis("off")
            axes[row][2].axis("off")
    if title:
        fig.suptitle(title)
    return _save(None, fig, path, 110)


def _save(plt, fig, path: str | Path, dpi: int, tight: bool = True) -> Path:
    """Lay out (``tight``: matplotlib's tight layout) and write the figure (its folder made)."""
    if tight:
        fig.tight_layout()
    return save_figure(fig, path, dpi=dpi)


@contextlib.contextmanager
def _headless_window():
    """Without an X display, ask VTK for an EGL render window for the plotters created inside (VTK
    would try X first and warn "bad X server connection"); the environment is restored after."""
    key = "VTK_DEFAULT_OPENGL_WINDOW"
    headless = os.name == "posix" and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if not headless or key in os.environ:
        yield
        return
    os.environ[key] = "vtkEGLRenderWindow"
    try:
        yield
    finally:
        os.environ.pop(key, None)


def _offscreen_plotter(window: tuple[int, int]):
    import pyvista as pv

    with _headless_window():
        return pv.Plotter(off_screen=True, window_size=list(window))


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
    with atomic_path(path, keep_suffix=True) as tmp:
        meshio.write(tmp, meshio.Mesh(points.reshape(-1, 3), [("quad", quads)], cell_data=data))
    return path


def _curved_field(result):
    """The CurvedTractionField of a conformal result, or None."""
    f = result.field
    return f if f is not None and getattr(f, "curved", None) is not None else None


def curved_strip_points(grid) -> np.ndarray:
    """Corner points (mx+1, ms+1, 3) of a curved grid on the rail surface (rail-profile frame:
    x rolling, y lateral, z down), the profile interpolated at the element edges along s."""
    y = np.interp(grid.s_edges, grid.rail_curve_s, grid.rail_curve[:, 0])
    z = np.interp(grid.s_edges, grid.rail_curve_s, grid.rail_curve[:, 1])
    return strip_points(grid.xl + np.arange(grid.mx + 1) * grid.dx, y, z)


def rail_surface_points(grid, x_margin: float = 5.0, nx: int = 30) -> np.ndarray:
    """The rail around the grid: its local profile curve extruded along x, (nx, n, 3)."""
    x = np.linspace(grid.xl - x_margin, grid.xl + grid.mx * grid.dx + x_margin, nx)
    return strip_points(x, grid.rail_curve[:, 0], grid.rail_curve[:, 1])


def wheel_surface_points(grid, x_margin: float = 5.0, nx: int = 30, x_range: tuple | None = None) -> np.ndarray:
    """The wheel around the grid: its profile revolved about the axle over the rolling range of the
    grid (or ``x_range``), (nx, k, 3) in the rail-profile frame (CurvedGrid wheel fields)."""
    a = np.asarray(grid.wheel_axle, float)
    d = np.asarray(grid.wheel_down, float)
    f = np.cross(a, d)
    R = float(grid.wheel_radius)
    x0, x1 = x_range or (grid.xl - x_margin, grid.xl + grid.mx * grid.dx + x_margin)
    x = np.linspace(x0, x1, nx)
    t = np.arcsin(np.clip(x / R, -1.0, 1.0))[:, None, None]
    yw, zw = grid.wheel_profile[:, 0][None, :, None], grid.wheel_profile[:, 1][None, :, None]
    return (np.asarray(grid.wheel_centre, float) + yw * a + (R + zw) * (np.cos(t) * d + np.sin(t) * f))


def _tangents(grid) -> tuple[np.ndarray, np.ndarray]:
    """(t_s, n) per column as 3-D vectors (ms, 3) in the rail-profile frame; t_s = n x e_x."""
    n = np.c_[np.zeros(grid.ms), grid.normal]
    t = np.c_[np.zeros(grid.ms), grid.normal[:, 1], -grid.normal[:, 0]]
    return t, n


def _boundary_segments(P: np.ndarray, status: np.ndarray, a: int, b: int) -> np.ndarray:
    """Cell edges (k, 2, 3) between cells of status a and b on a strip with corners P."""
    segs = []
    s0, s1 = status[:-1, :], status[1:, :]           # neighbours along x: edge at x index i+1
    i, j = np.nonzero(((s0 == a) & (s1 == b)) | ((s0 == b) & (s1 == a)))
    segs += [np.stack([P[i + 1, j], P[i + 1, j + 1]], axis=1)]
    s0, s1 = status[:, :-1], status[:, 1:]           # neighbours along s: edge at s index j+1
    i, j = np.nonzero(((s0 == a) & (s1 == b)) | ((s0 == b) & (s1 == a)))
    segs += [np.stack([P[i, j + 1], P[i + 1, j + 1]], axis=1)]
    return np.concatenate(segs, axis=0)


def _polylines(segs: np.ndarray):
    import pyvista as pv

    if len(segs) == 0:
        return None
    pts = segs.reshape(-1, 3)
    lines = np.c_[np.full(len(segs), 2), np.arange(0, 2 * len(segs), 2), np.arange(1, 2 * len(segs), 2)]
    return pv.PolyData(pts, lines=lines.ravel())


def conformal_meshes(result) -> dict:
    """pyvista meshes of a conformal result, all in the rail-profile frame of the side: ``strip``
    (the curved grid with cell data pn, px, ps, pt, status, delta, h, un and the 3-D tangential
    traction vector ``traction``), ``rail``, ``wheel`` (surfaces around the contact) and the
    ``slip_boundary`` / ``contact_boundary`` lines (None where there are none)."""
    f = _curved_field(result)
    if f is None:
        raise ValueError("conformal_meshes: the result has no curved traction field (theory \"conformal\")")
    g = f.curved
    P = curved_strip_points(g)
    pn, px, ps = f.side_frame("pn"), f.side_frame("px"), f.side_frame("py")
    status = f.side_frame("status")
    t, n = _tangents(g)
    T = px[..., None] * np.array([1.0, 0.0, 0.0]) + ps[..., None] * t[None, :, :]
    cells = {"pn": pn, "px": px, "ps": ps, "pt": np.hypot(px, ps), "status": status.astype(float),
             "delta_deg": np.degrees(f.side_frame("delta")), "h": f.side_frame("h"),
             "un": f.side_frame("un") if f.un is not None else np.zeros_like(pn), "traction": T}
    # lifted off the rail surface towards the wheel (drawn on top of it, no z-fighting)
    size = max(np.ptp(P[..., 1]), np.ptp(P[..., 2]), g.dx * g.mx)
    n_edges = np.r_[n, n[-1:]][None, :, :]
    Pl = P - 0.008 * size * n_edges
    return {"strip": strip_mesh(P - 0.004 * size * n_edges, cells), "rail": strip_mesh(rail_surface_points(g)),
            "wheel": strip_mesh(wheel_surface_points(g)), "points": P,
            "slip_boundary": _polylines(_boundary_segments(Pl, status, ADHESION, SLIP)),
            "contact_boundary": _polylines(np.concatenate([_boundary_segments(Pl, status, 0, ADHESION),
                                                           _boundary_segments(Pl, status, 0, SLIP)]))}


def plot3d(result, plotter=None, *, scalar: str = "pn", bodies: bool = True):
    """Add a result to a pyvista Plotter and return the plotter (nothing is shown or written).

    A conformal result (curved grid) gives the rail (grey) and the wheel (translucent, cut at the
    trailing edge of the grid) around the contact, the contact strip coloured by ``scalar``, the
    tangential tractions (black arrows), the slip/adhesion boundary (red) and the edge of the
    contact (white), in the rail-profile frame of the side (x rolling, y lateral, z down, mm).
    A planar result is drawn as its flat traction field (x, y, z = 0).

    Parameters
    ----------
    result : conformal.result.Result
        A result with a traction field (theories exact, conformal, fastsim).
    plotter : pyvista.Plotter, optional
        The plotter to draw into (e.g. ``pyvista.Plotter()`` in a notebook, then ``.show()``); an
        off-screen plotter when omitted.
    scalar : {"pn", "pt", "px", "ps"}
        The colouring of the contact strip.
    bodies : bool
        Draw the rail and wheel surfaces (conformal results).

    Returns
    -------
    pyvista.Plotter
    """
    import pyvista as pv

    if plotter is None:
        plotter = _offscreen_plotter((1000, 800))
    label = {"pn": "p_n [N/mm²]", "pt": "|p_t| [N/mm²]", "px": "p_x [N/mm²]", "ps": "p_s [N/mm²]"}.get(scalar, scalar)
    # horizontal, below the view: beside it the bar covered the wheel
    # two labels (0 and the maximum) at the ends: a middle label ran into the centred title
    bar = {"title": label, "color": "black", "n_labels": 2, "fmt": "%.4g", "vertical": False,
           "position_x": 0.25, "position_y": 0.03, "width": 0.5, "height": 0.07,
           "title_font_size": 22, "label_font_size": 20}
    if _curved_field(result) is None:
        f = result.field if result.field is not None else None
        if f is None and result.patches:
            f = max(result.patches, key=lambda r: r.FN).field
        if f is None:
            raise ValueError("plot3d: the result has no traction field (theory hertz, linear or empirical)")
        xe, ye = _edges(f.grid)
        cells = {"pn": f.pn, "px": f.px, "ps": f.py, "pt": np.hypot(f.px, f.py), "status": f.status.astype(float)}
        mesh = strip_mesh(strip_points(xe, ye, np.zeros_like(ye)), cells)
        plotter.add_mesh(mesh, scalars=scalar, cmap="viridis", show_edges=True, edge_color="#404040",
                         clim=(0.0, max(float(np.max(cells[scalar])), 1e-12)) if scalar in ("pn", "pt") else None,
                         scalar_bar_args=bar)
        return plotter
    m = conformal_meshes(result)
    g = result.field.curved
    strip = m["strip"]
    L = max(g.mx * g.dx, float(g.s_edges[-1] - g.s_edges[0]), 10.0)
    if bodies:
        plotter.add_mesh(m["rail"], color="#b0b0b0", smooth_shading=True)
        # up to 0.8 L behind the grid: 1.5 L ran out of the picture (the wheel was cut off)
        cut = strip_mesh(wheel_surface_points(g, x_range=(g.xl - 0.8 * L, g.xl)))
        plotter.add_mesh(cut, color="#d9b38c", opacity=0.55, smooth_shading=True)
    contact = strip.threshold(0.5, scalars="status")
    plotter.add_mesh(strip, color="#e8e8e8", show_edges=True, edge_color="#909090", line_width=0.5)
    if contact.n_cells:
        vmax = max(float(np.max(contact.cell_data[scalar])), 1e-12)
        plotter.add_mesh(contact, scalars=scalar, cmap="viridis", show_edges=True, edge_color="#404040",
                         line_width=0.5, clim=(0.0, vmax) if scalar in ("pn", "pt") else None,
                         scalar_bar_args=bar)
        T = np.asarray(contact.cell_data["traction"])
        tmax = float(np.abs(T).max())
        if tmax > 0:
            # readable arrows: at most about ARROWS_3D of them (every k-th contact element), each up
            # to 3 (thinned) elements long; lifted above the strip so that they are not hidden in it
            cen = contact.cell_centers()
            k = max(1, int(np.ceil(np.sqrt(contact.n_cells / ARROWS_3D))))
            keep = np.arange(contact.n_cells)[::k * k] if k > 1 else np.arange(contact.n_cells)
            pts = pv.PolyData(np.asarray(cen.points)[keep])
            pts["traction"] = T[keep]
            size = 1.1 * k * max(g.dx, float(g.ds.mean()))
            plotter.add_mesh(pts.glyph(orient="traction", scale="traction", factor=size / tmax,
                                       geom=pv.Arrow(tip_length=0.4, tip_radius=0.2, shaft_radius=0.07)),
                             color="black")
    for key, colour in (("slip_boundary", "red"), ("contact_boundary", "white")):
        if m[key] is not None:
            plotter.add_mesh(m[key], color=colour, line_width=4)
    # camera: from the wheel side of the reference normal, turned towards the rolling direction
    c = np.asarray(strip.center)
    k = int(np.argmin(np.abs(g.s - g.s_ref)))
    n = np.r_[0.0, g.normal[k]]
    t = np.r_[0.0, g.normal[k, 1], -g.normal[k, 0]]
    view = -1.0 * n + 0.9 * np.array([1.0, 0.0, 0.0]) + 0.35 * t
    # orientation and scale (before the camera: adding actors may reset it): the frame's axes
    # (lower left) and a ruler across the strip's leading edge (x = xl, along s; the view looks
    # nearly along x, which would foreshorten a ruler along x)
    # the view looks nearly along x: the triad's x and z labels fell on each other, so the triad
    # has no labels and a legend beside it names its colours
    plotter.add_axes(labels_off=True, line_width=4, viewport=(0.0, 0.12, 0.18, 0.34))
    plotter.add_text("axes: x rolling (red)\n  y lateral (green)\n  z down (blue)", position=(0.005, 0.02),
                     viewport=True, font_size=11, color="black")
    ruler = _ruler_length(L)
    a = np.asarray(m["points"][0, 0], dtype=float) - 0.02 * L * np.r_[0.0, g.normal[0]]
    b = a + ruler * _tangents(g)[0][0]
    plotter.add_mesh(pv.Line(a, b), color="black", line_width=6)
    plotter.add_point_labels(np.array([0.5 * (a + b)]), [f"{ruler:g} mm"], font_size=22, text_color="black",
                             shape_opacity=0.6, shape_color="white", always_visible=True, show_points=False)
    plotter.camera.focal_point = c
    # far enough that the wheel above the strip is not cut off by the picture's edge (2.2 L did)
    plotter.camera.position = c + 5.2 * L * view / np.linalg.norm(view)
    plotter.camera.up = (0.0, 0.0, -1.0)        # z is down in the rail-profile frame
    # the scene up by a tenth of the picture: the colour bar and the legend below it keep clear of
    # the rail (the bar lay on the rail's lower edge)
    d = np.asarray(plotter.camera.position) - c
    up = np.array([0.0, 0.0, -1.0]) - d * (-d[2]) / float(d @ d)
    up /= np.linalg.norm(up)
    height = 2.0 * np.linalg.norm(d) * np.tan(np.radians(plotter.camera.view_angle) / 2.0)
    shift = -0.05 * height * up
    plotter.camera.focal_point = c + shift
    plotter.camera.position = c + d + shift
    return plotter


def _ruler_length(span: float) -> float:
    """A round length (1, 2 or 5 times a power of ten) of about a third of ``span`` (mm)."""
    target = max(span / 3.0, 1e-9)
    e = 10.0 ** np.floor(np.log10(target))
    return float(max((f * e for f in (1.0, 2.0, 5.0) if f * e <= target), default=e))


def _render_into(pl, result, scalar: str, title: str) -> np.ndarray:
    pl.set_background("white")
    plot3d(result, pl, scalar=scalar)
    if title:
        pl.add_text(title, font_size=10, color="black")
    img = pl.screenshot(return_img=True)
    pl.close()
    return img


def render_conformal_3d(result, *, scalar: str = "pn", window: tuple[int, int] = (1000, 800),
                        title: str = "") -> np.ndarray:
    """Off-screen image (RGB array) of a conformal result as drawn by :func:`plot3d`, seen from
    ahead so that the contact face the wheel covers is visible."""
    return _render_into(_offscreen_plotter(window), result, scalar, title)


def _render_child(conn, window: tuple[int, int], scalar: str) -> None:
    """Helper process of :class:`Render3D`: open the off-screen window, wait for a result, render."""
    try:
        pl = _offscreen_plotter(window)           # imports pyvista/VTK and opens the window
        result = conn.recv()
        if result is None:
            pl.close()
            return
        conn.send(("ok", _render_into(pl, result, scalar, "")))
    except BaseException as exc:  # noqa: BLE001 - reported to the parent, which renders itself
        try:
            conn.send(("error", f"{type(exc).__name__}: {exc}"))
        except Exception:
            pass
    finally:
        conn.close()


class Render3D:
    """The 3-D view of :func:`render_conformal_3d`, drawn by a helper process started early.

    Importing pyvista/VTK and opening an off-screen window costs about 1 s, rendering 0.3-0.5 s;
    ``conformal demo`` starts the helper before the solve (a forked copy of this process, so
    nothing is imported twice), hands it the result with :meth:`send` and collects the image
    with :meth:`image` after drawing the matplotlib panels, so both overlap on two cores.  Where
    no process can be forked, or the helper fails, :meth:`image` renders in this process: the
    picture is the same either way.  ``process=False``: always in this process.
    """

    def __init__(self, window: tuple[int, int] = (1000, 800), scalar: str = "pn", *, process: bool = True):
        self.window, self.scalar = tuple(window), scalar
        self._conn = self._proc = self._result = None
        self._waiting = False         # the helper waits for a result (close() must release it)
        import multiprocessing as mp

        if not process or "fork" not in mp.get_all_start_methods():
            return
        ctx = mp.get_context("fork")
        parent, child = ctx.Pipe()
        try:
            self._proc = ctx.Process(target=_render_child, args=(child, self.window, scalar), daemon=True)
            self._proc.start()
        except OSError:
            self._proc = None
            parent.close()
        else:
            self._conn = parent
            self._waiting = True
        finally:
            child.close()

    def send(self, result) -> None:
        """Hand the result to the helper (it renders while this process goes on)."""
        self._result = result
        if self._conn is not None:
            try:
                self._conn.send(result)
                self._waiting = False
            except Exception:  # noqa: BLE001 - unpicklable result or helper gone: render here
                self.close()

    def image(self) -> np.ndarray:
        """The RGB image of the result given to :meth:`send`."""
        if self._result is None:
            raise ValueError("Render3D.image: no result was sent")
        img = None
        if self._conn is not None:
            try:
                status, value = self._conn.recv()
                img = value if status == "ok" else None
            except (EOFError, OSError):
                img = None
        self.close()
        if img is None:
            img = render_conformal_3d(self._result, scalar=self.scalar, window=self.window)
        return img

    def close(self) -> None:
        """Stop the helper (if it still waits) and release it."""
        if self._conn is not None:
            try:
                if self._waiting and self._proc is not None and self._proc.is_alive():
                    self._conn.send(None)           # no result will come: let it go
            except (OSError, ValueError):
                pass
            self._waiting = False
            self._conn.close()
            self._conn = None
        if self._proc is not None:
            self._proc.join(timeout=10)
            if self._proc.is_alive():
                self._proc.kill()
                self._proc.join()
            self._proc = None


WINDOW_3D = (1100, 1300)  # pixels of the 3-D view in plot_conformal_result (the height of its panel)
#: about this many tangential-traction arrows in the 3-D view (more are unreadable)
ARROWS_3D = 150


def plot_conformal_result(result, path: str | Path, title: str | None = None, *,
                          render: Render3D | None = None) -> Path:
    """One PNG of a conformal result: the 3-D view of rail, wheel and tractions (pyvista), the
    developed maps (pressure, tangential traction, adhesion/slip) and the pressure and contact
    angle along the profile.  ``render``: a :class:`Render3D` started earlier (it gets the result
    here and draws while the maps are drawn), else the view is rendered here."""
    f = _curved_field(result)
    if render is None:             # in this process (a library call: no helper process)
        render = Render3D(WINDOW_3D, process=False)
    render.send(result)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(17, 9.5))
    # fixed margins instead of the tight layout (0.2 s of the demo's 2-3 s), 85 dpi (PNG 0.1 s less)
    gs = fig.add_gridspec(3, 3, width_ratios=[2.2, 1, 1], height_ratios=[1, 1, 1], left=0.005, right=0.955,
                          bottom=0.06, top=0.955, wspace=0.42, hspace=0.42)
    ax3 = fig.add_subplot(gs[:, 0])
    ax3.axis("off")
    fy_track = result.extra.get("FY_track", float("nan"))
    scale = max(abs(result.FN), abs(result.FX), abs(result.FY))
    ax3.set_title(f"{title or result.extra.get('label', '')}\nFN {result.FN:.5g} N, {_forces_title(result)} "
                  f"(contact plane)\nFY_track {force_text(fy_track, scale) if fy_track == fy_track else 'nan'} N "
                  f"(track lateral), pmax {result.pmax:.4g} N/mm²", fontsize=10)
    maps = [fig.add_subplot(gs[0, 1]), fig.add_subplot(gs[1, 1]), fig.add_subplot(gs[2, 1])]
    _draw_field(fig, maps, result, "developed")
    for a in maps:
        a.set_ylabel(a.get_ylabel().replace("y [mm]", "s - s_ref [mm]"))
    g = f.curved
    ax = fig.add_subplot(gs[0:2, 2])
    P = curved_strip_points(g)
    ax.plot(g.rail_curve[:, 0], g.rail_curve[:, 1], color="grey", lw=2, label="rail")
    W = wheel_surface_points(g, nx=3)[1]
    ax.plot(W[:, 1], W[:, 2], color="#b07030", lw=1.5, label="wheel (x = 0)")
    cols = np.flatnonzero((f.side_frame("status") != 0).any(axis=0))
    if cols.size:
        ax.plot(P[0, cols[0]:cols[-1] + 2, 1], P[0, cols[0]:cols[-1] + 2, 2], color="red", lw=4, label="contact")
    ax.invert_yaxis()
    ax.set_aspect("equal")
    ax.set_xlabel("y [mm] (rail profile)")
    ax.set_ylabel("z [mm] (down)")
    ax.legend(fontsize=8)
    ax.set_title(f"contact angle {np.degrees(g.delta.min()):.1f} .. {np.degrees(g.delta.max()):.1f} deg on the grid",
                 fontsize=9)
    ax = fig.add_subplot(gs[2, 2])
    sc = g.s - g.s_ref
    pn = f.side_frame("pn")
    ax.plot(sc, pn.max(axis=0), color="C0", label="max over x of p_n")
    ax.set_xlabel("s - s_ref [mm] (side frame)")
    ax.set_ylabel("p_n [N/mm²]")
    ax2 = ax.twinx()
    ax2.plot(sc, np.degrees(g.delta), color="C3", ls="--", label="contact angle")
    ax2.set_ylabel("delta [deg]", color="C3")
    ax.legend(fontsize=8, loc="upper left")
    ax3.imshow(render.image())
    return _save(None, fig, path, 85, tight=False)


def export_conformal_vtu(result, path: str | Path) -> list[Path]:
    """VTU files of a conformal result for ParaView (meshio): ``path`` holds the contact strip with
    the per-element data of :func:`conformal_meshes`; ``<stem>_rail.vtu`` and ``<stem>_wheel.vtu``
    the surfaces around it.  All in the rail-profile frame of the side (x rolling, y lateral,
    z down), mm and N/mm²."""
    m = conformal_meshes(result)
    f = _curved_field(result)
    g = f.curved
    P = m["points"]
    cells = {k: np.asarray(m["strip"].cell_data[k]).reshape(g.ms, g.mx, *np.shape(m["strip"].cell_data[k])[1:])
             .swapaxes(0, 1) for k in m["strip"].cell_data.keys()}
    path = Path(path)
    out = [export_vtu(path, P, cells)]
    for name, pts in (("rail", rail_surface_points(g)), ("wheel", wheel_surface_points(g))):
        out.append(export_vtu(path.with_name(f"{path.stem}_{name}.vtu"), pts, {}))
    return out


def export_result_vtu(result, path: str | Path) -> list[Path]:
    """``conformal solve --vtu``: the VTU files of a conformal result (:func:`export_conformal_vtu`);
    other theories have no curved surface to export (InputError says so)."""
    from conformal.errors import InputError

    if _curved_field(result) is None:
        raise InputError(f"--vtu: needs [model] theory = \"conformal\" (tractions on the curved surfaces); "
                         f"this result is {result.theory!r}")
    return export_conformal_vtu(result, path)
