"""Figures and VTU files of stress fields (N/mm², mm).

* :func:`write_stress_vtu`: the block of a :class:`~conformal.stresses.field.StressField` as
  hexahedra with the stress components and invariants at the points (meshio, atomic write);
* :func:`plot_stress_field`: von Mises and orthogonal shear on the slice along the rolling
  direction and on the cross-section through the maximum, and the Dang Van index per depth.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from conformal.files import atomic_path, save_figure

_COMPONENTS = (("sigma_xx", 0, 0), ("sigma_yy", 1, 1), ("sigma_zz", 2, 2), ("sigma_xy", 0, 1),
               ("sigma_xz", 0, 2), ("sigma_yz", 1, 2))


def _hexahedra(nd: int, n1: int, n2: int) -> np.ndarray:
    idx = np.arange(nd * n1 * n2).reshape(nd, n1, n2)
    c = [idx[:-1, :-1, :-1], idx[:-1, 1:, :-1], idx[:-1, 1:, 1:], idx[:-1, :-1, 1:],
         idx[1:, :-1, :-1], idx[1:, 1:, :-1], idx[1:, 1:, 1:], idx[1:, :-1, 1:]]
    return np.stack([a.ravel() for a in c], axis=-1)


def write_stress_vtu(sf, path: str | Path) -> Path:
    """Write the stress block ``sf`` (StressField) to a VTU file (hexahedra; point data: the six
    stress components, von_mises, principal_shear, orthogonal_shear, max_principal)."""
    import meshio

    path = Path(path)
    nd, n1, n2 = sf.sigma.shape[:3]
    pts = sf.points.reshape(-1, 3)
    data = {name: sf.sigma[..., i, j].ravel() for name, i, j in _COMPONENTS}
    data.update(von_mises=sf.von_mises.ravel(), principal_shear=sf.principal_shear.ravel(),
                orthogonal_shear=sf.orthogonal_shear.ravel(), max_principal=sf.max_principal.ravel(),
                depth=np.broadcast_to(sf.depths[:, None, None], (nd, n1, n2)).ravel().copy())
    cells = [("hexahedron", _hexahedra(nd, n1, n2))] if min(nd, n1, n2) > 1 else [("vertex", np.arange(len(pts))[:, None])]
    mesh = meshio.Mesh(pts, cells, point_data=data)
    with atomic_path(path, keep_suffix=True) as tmp:
        meshio.write(tmp, mesh)
    return path


def plot_stress_field(sf, path: str | Path, title: str = "", dang_van_alpha: float = 1.0 / 3.0,
                      surface: np.ndarray | None = None) -> Path:
    """Three panels: von Mises on the slice (x, depth) through its maximum, von Mises on the
    cross-section through it (planar: (y, depth); conformal strip: (y, z) of the rail-profile
    frame, with the rail ``surface`` curve (n, 2) when given) and the orthogonal shear there."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from conformal.stresses.fatigue import dang_van

    vm = sf.von_mises
    orth = sf.orthogonal_shear
    d_i, x_i, c_i = np.unravel_index(int(np.nanargmax(vm)), vm.shape)
    fig = Figure(figsize=(15, 4.6), constrained_layout=True)
    ax1, ax2, ax3, ax4 = fig.subplots(1, 4, gridspec_kw={"width_ratios": [1.2, 1.2, 1.2, 0.9]})
    X = sf.points[:, :, c_i, 0]
    D = np.broadcast_to(sf.depths[:, None], X.shape)
    m1 = ax1.pcolormesh(X, D, vm[:, :, c_i], shading="gouraud", cmap="viridis")
    ax1.invert_yaxis()
    ax1.set(xlabel="x, rolling direction (mm)", ylabel="depth (mm)",
            title=f"von Mises, slice through the max\n(column {c_i})")
    fig.colorbar(m1, ax=ax1, label="von Mises (N/mm²)")
    for ax, val, name, cmap in ((ax2, vm[:, x_i], "von Mises", "viridis"),
                                (ax3, orth[:, x_i], "orthogonal shear σ_xn", "RdBu_r")):
        if sf.frame == "planar":
            Y = sf.points[:, x_i, :, 1]
            Dz = np.broadcast_to(sf.depths[:, None], Y.shape)
            m = ax.pcolormesh(Y, Dz, val, shading="gouraud", cmap=cmap,
                              **({"vmin": -np.abs(val).max(), "vmax": np.abs(val).max()} if cmap == "RdBu_r" else {}))
            ax.invert_yaxis()
            ax.set(xlabel="y (mm)", ylabel="depth (mm)")
        else:
            Y, Z = sf.points[:, x_i, :, 1], sf.points[:, x_i, :, 2]
            m = ax.pcolormesh(Y, Z, val, shading="gouraud", cmap=cmap,
                              **({"vmin": -np.abs(val).max(), "vmax": np.abs(val).max()} if cmap == "RdBu_r" else {}))
            if surface is not None:
                ax.plot(surface[:, 0], surface[:, 1], "k-", lw=1.0, label="rail surface")
                ax.legend(loc="lower left", fontsize=7)
            ax.set_aspect("equal")
            pad = 0.5 * float(sf.depths.max())
            ax.set_xlim(Y.min() - pad, Y.max() + pad)
            ax.set_ylim(Z.max() + pad, Z.min() - pad)
            ax.set(xlabel="y, rail profile frame (mm)", ylabel="z, down (mm)")
        ax.set_title(f"{name}\ncross-section at x = {sf.points[0, x_i, 0, 0]:.2f} mm")
        fig.colorbar(m, ax=ax, label=f"{name} (N/mm²)")
    tau_dv, _ = dang_van(sf.sigma, dang_van_alpha, axis=1)
    ax4.plot(tau_dv.max(axis=1), sf.depths, "C3-", label="Dang Van τ_a + α σ_h")
    ax4.plot(sf.principal_shear.max(axis=(1, 2)), sf.depths, "C0--", label="(s1 - s3)/2")
    ax4.plot(np.abs(orth).max(axis=(1, 2)), sf.depths, "C2:", label="|σ_xn|")
    ax4.invert_yaxis()
    ax4.set(xlabel="max over the plane (N/mm²)", ylabel="depth (mm)", title="per depth")
    ax4.legend(fontsize=7)
    if title:
        fig.suptitle(title)
    return save_figure(fig, path, dpi=110)


def plot_section_comparison(points, sigma_hs, sigma_fe, path, title: str = "", surface=None,
                            body_label: str = "FE rail") -> Path:
    """von Mises on a cross-section (points (nd, nc, 3), rail-profile frame) of the half-space
    and of the FE body, and their difference (N/mm²)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from conformal.stresses.invariants import von_mises

    Y, Z = points[..., 1], points[..., 2]
    v_hs, v_fe = von_mises(sigma_hs), von_mises(sigma_fe)
    fig = Figure(figsize=(13, 4.4), constrained_layout=True)
    axes = fig.subplots(1, 3)
    lim = (min(v_hs.min(), v_fe.min()), max(v_hs.max(), v_fe.max()))
    d = v_fe - v_hs
    for ax, val, name, kw in ((axes[0], v_hs, "half-space\n(elements on their tangent planes)", {"vmin": lim[0], "vmax": lim[1]}),
                              (axes[1], v_fe, f"{body_label}\n(half-space + FE correction, P1)", {"vmin": lim[0], "vmax": lim[1]}),
                              (axes[2], d, f"\n{body_label} - half-space", {"cmap": "RdBu_r", "vmin": -np.abs(d).max(),
                                                                     "vmax": np.abs(d).max()})):
        m = ax.pcolormesh(Y, Z, val, shading="gouraud", **kw)
        if surface is not None:
            ax.plot(surface[:, 0], surface[:, 1], "k-", lw=1.0)
        ax.set_aspect("equal")
        pad = 0.3 * float(np.ptp(Z) + np.ptp(Y)) / 2
        ax.set_xlim(Y.min() - pad, Y.max() + pad)
        ax.set_ylim(Z.max() + pad, Z.min() - pad)
        ax.set(xlabel="y, rail profile frame (mm)", ylabel="z, down (mm)", title=f"von Mises, {name}")
        fig.colorbar(m, ax=ax, label="N/mm²")
    if title:
        fig.suptitle(title)
    return save_figure(fig, path, dpi=110)


def plot_section_3d(result, points, values, path, *, title: str = "", label: str = "von Mises (N/mm²)",
                    window: tuple[int, int] = (1300, 950), body: str = "rail") -> Path:
    """Off-screen pyvista PNG: the rail around a conformal strip (grey), the contact patch coloured
    by its pressure and a cross-section of the rail head (points (nd, nc, 3), rail-profile frame)
    coloured by ``values`` (nd, nc), with axes in mm; ``body = "wheel"``: the wheel's surface
    instead of the rail's, for a section through the wheel."""
    from conformal.plots import _offscreen_plotter, conformal_meshes, strip_mesh

    meshes = conformal_meshes(result)
    P = np.asarray(points, float)
    x0 = float(P[..., 0].mean())
    section = strip_mesh(P)
    section.point_data[label] = np.asarray(values, float).T.reshape(-1)
    pl = _offscreen_plotter(window)
    # the rail and the patch ahead of the section (x >= x0): the cut face is in view
    rail = meshes[body].clip(normal=(-1.0, 0.0, 0.0), origin=(x0, 0.0, 0.0))
    pl.add_mesh(rail, color="lightgrey", opacity=0.45)
    strip = meshes["strip"].threshold(1e-9, scalars="pn").clip(normal=(-1.0, 0.0, 0.0), origin=(x0, 0.0, 0.0))
    bar = {"vertical": True, "height": 0.6, "width": 0.05, "title_font_size": 14, "label_font_size": 12}
    pl.add_mesh(strip, scalars="pn", cmap="inferno",
                scalar_bar_args={"title": "pressure pn (N/mm²)", "position_x": 0.06, "position_y": 0.2, **bar})
    pl.add_mesh(section, scalars=label, cmap="viridis",
                scalar_bar_args={"title": label, "position_x": 0.88, "position_y": 0.2, **bar})
    pl.show_bounds(mesh=section, xtitle="x (mm)", ytitle="y (mm)", ztitle="z, down (mm)", font_size=12,
                   location="outer")
    if title:
        pl.add_text(title, font_size=11)
    c = P.reshape(-1, 3).mean(axis=0)
    span = float(np.ptp(P[..., 1]) + np.ptp(P[..., 2]))
    pl.camera.focal_point = tuple(c)
    # from above the rail; a wheel section from below, so that the patch is not behind the wheel
    pl.camera.position = tuple(c + span * np.array([-2.2, -0.5, -0.9 if body == "rail" else 0.9]))
    pl.camera.up = (0.0, 0.0, -1.0)
    path = Path(path)
    try:
        with atomic_path(path, keep_suffix=True) as tmp:
            pl.screenshot(tmp)
    finally:
        pl.close()
    return path
