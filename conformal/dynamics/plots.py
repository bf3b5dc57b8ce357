"""Figures of a wheelset run like the seed's Figs. 11-15, and the damping-ratio curve."""
from __future__ import annotations

from pathlib import Path


from conformal.files import save_figure


class _Unregistered:
    """Stands in for pyplot where a figure is closed: our figures are never registered with it."""

    @staticmethod
    def close(fig) -> None:
        fig.clear()


def _fig(nrows: int = 1):
    """A matplotlib Figure not registered with pyplot (no backend switch, nothing global)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 3.0 + 1.8 * (nrows - 1)))
    ax = fig.subplots(nrows, 1, sharex=True, squeeze=False)
    return _Unregistered, fig, ax[:, 0]


def history_figures(history: dict, title: str = "") -> dict:
    """The figures of :func:`plot_history` by file name (matplotlib Figures, not written)."""
    t = history["t"]
    figs = {}

    _, fig, ax = _fig()
    ax[0].plot(t, history["y"], "b-")
    ax[0].set_ylabel("lateral displacement y [mm]")
    ax[0].set_xlabel("time [s]")
    ax[0].set_title(f"{title} wheelset lateral displacement (seed Fig. 11)".strip())
    ax[0].grid(alpha=0.3)
    figs["fig11_lateral.png"] = fig

    _, fig, ax = _fig(3)
    ax[0].plot(t, history["right_xi"], "b-")
    ax[0].set_ylabel("xi [-]")
    ax[1].plot(t, history["right_eta"], "r-")
    ax[1].set_ylabel("eta [-]")
    # in the CSV's unit (history.csv: right_phi in rad/mm), not rescaled
    ax[2].plot(t, history["right_phi"], "g-")
    ax[2].set_ylabel("spin phi [rad/mm]")
    ax[2].set_xlabel("time [s]")
    ax[0].set_title("right wheel: longitudinal, lateral and spin creepage (seed Fig. 12)")
    for a in ax:
        a.grid(alpha=0.3)
    figs["fig12_creepages.png"] = fig

    _, fig, ax = _fig()
    ax[0].plot(t, history["right_a"], "b-", label="a (rolling direction)")
    ax[0].plot(t, history["right_b"], "r-", label="b (lateral)")
    ax[0].set_ylabel("semi-axis [mm]")
    ax[0].set_xlabel("time [s]")
    ax[0].legend()
    ax[0].set_title("right wheel: contact semi-axes (seed Fig. 13)")
    ax[0].grid(alpha=0.3)
    figs["fig13_semiaxes.png"] = fig

    _, fig, ax = _fig()
    ax[0].plot(t, history["right_FZ"] / 1000.0, "b-")
    ax[0].set_ylabel("vertical force FZ [kN]")
    ax[0].set_xlabel("time [s]")
    ax[0].set_title("right wheel: vertical contact force (seed Fig. 14)")
    ax[0].grid(alpha=0.3)
    figs["fig14_vertical_force.png"] = fig

    _, fig, ax = _fig(2)
    ax[0].plot(t, history["right_FX"] / 1000.0, "b-")
    ax[0].set_ylabel("longitudinal FX [kN]")
    ax[1].plot(t, history["right_FY"] / 1000.0, "r-")
    ax[1].set_ylabel("lateral FY [kN]")
    ax[1].set_xlabel("time [s]")
    ax[0].set_title("right wheel: longitudinal and lateral contact forces (seed Fig. 15)")
    for a in ax:
        a.grid(alpha=0.3)
    figs["fig15_forces.png"] = fig
    return figs


def plot_history(history: dict, out: str | Path, title: str = "") -> list[Path]:
    """fig11_lateral.png (wheelset lateral displacement), fig12_creepages.png (right wheel
    xi, eta, spin in rad/mm as in history.csv), fig13_semiaxes.png (right wheel a, b),
    fig14_vertical_force.png (right wheel), fig15_forces.png (right wheel longitudinal and lateral
    forces)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fig in history_figures(history, title).items():
        fig.tight_layout()
        p = save_figure(fig, out / name, dpi=110)
        _Unregistered.close(fig)
        paths.append(p)
    return paths


#: the critical speed of the seed's wheelset (Valtorta et al. 2001, m/s): drawn for that vehicle only
SEED_CRITICAL_SPEED = 69.0


def damping_figure(speeds, zeta, freq, critical: float | None = None, nonlinear: float | None = None,
                   reference: float | None = None, title: str = ""):
    """The figure of :func:`plot_damping` (a matplotlib Figure, not written)."""
    _, fig, ax = _fig(2)
    ax[0].plot(speeds, zeta, "b-")
    ax[0].axhline(0.0, color="k", lw=0.8)
    ax[0].set_ylabel("damping ratio [-]")
    for v, lab, c, ls in ((critical, "linear critical", "r", "--"), (nonlinear, "nonlinear onset", "m", ":"),
                          (reference, "seed (Valtorta et al. 2001)", "g", "-.")):
        if v is not None:
            ax[0].axvline(v, color=c, ls=ls, lw=1, label=f"{lab}: {v:.1f} m/s")
            ax[1].axvline(v, color=c, ls=ls, lw=1)
    if ax[0].get_legend_handles_labels()[0]:
        ax[0].legend(fontsize=8, loc="lower left")
    ax[1].plot(speeds, freq, "k-")
    ax[1].set_ylabel("frequency [Hz]")
    ax[1].set_xlabel("speed [m/s]")
    ax[0].set_title(f"{title} least-damped mode of the linear model".strip())
    for a in ax:
        a.grid(alpha=0.3)
    return fig


def plot_damping(speeds, zeta, freq, out: str | Path, critical: float | None = None,
                 nonlinear: float | None = None, reference: float | None = None, title: str = "") -> Path:
    """Damping ratio (and frequency) of the least-damped mode versus speed, with this vehicle's
    linear critical speed (and nonlinear onset); ``reference``: a published critical speed of the
    same vehicle (the seed's wheelset: SEED_CRITICAL_SPEED), drawn only where given."""
    fig = damping_figure(speeds, zeta, freq, critical, nonlinear, reference, title)
    fig.tight_layout()
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    p = save_figure(fig, out, dpi=110)
    _Unregistered.close(fig)
    return p
