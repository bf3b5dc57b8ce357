"""Equations of motion of a suspended wheelset on tangent track (seed section "Implementation in
multibody codes", Eqs. 50-61, Table 1).

Coordinates (track frame: x forward, y to the right, z down; SI units): the wheelset centre moves
with the frame at the constant speed V along x; its degrees of freedom are the lateral
displacement y, the vertical displacement z, the roll phi (about x) and the yaw psi (about z),
state X = (y, z, phi, psi, y', z', phi', psi').  The wheelset spins at the constant rate
Omega = -V/r0 about its axle a = Rx(phi) Rz(psi) e_y (r0: rolling radius at centred running), so
its angular momentum adds the gyroscopic couples +Iyy Omega psi' (roll) and -Iyy Omega phi' (yaw).
The primary suspension (two longitudinal springs/dampers kx, cx at +-b, two lateral ones ky, cy)
ties it to the frame; the vertical load W per wheel (the wheelset's own weight included) acts
at the axle.

Contact per wheel (side frame of the wheel's rail, y towards its field side): the wheel's lateral
shift over its rail is y_r = s (y - Delta(x) - r0 phi) (s = +1 right, -1 left; Delta the
alignment of that rail, r0 phi the lateral move of the contact point under roll), the height of
the wheel y_zeta = z + s L phi.  Each patch (tread, flange) of the contact table touches at the
height Z(y_r); the overlap along the normal is p = n_z (zeta - Z(y_r)) (Eq. 56) and the elastic
energy U = 2/5 Kh p^2.5 (Hertz, F = Kh p^1.5); its gradient gives the normal contact forces, and
Eq. 57's damping C pdot p acts along the same direction.  Creepages follow from the wheelset
velocities at the contact point (Eqs. 58-61) and the creep forces act at the contact point in the
patch frame.

>>> from conformal.dynamics.scene import EXAMPLE, scene_from_dict
>>> import tomllib
>>> s = scene_from_dict(tomllib.loads(EXAMPLE.replace('creep_model = "fastsim"', 'creep_model = "none"')))
>>> m = build_model(s, table_step=0.5, table_range=2.0)
>>> X = equilibrium(m)
>>> out = m.outputs(0.0, X)
>>> round(out["right_FZ"] / 49000.0, 6), round(out["left_FZ"] / 49000.0, 6)
(1.0, 1.0)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import fsolve

from conformal.dynamics.contact import C, ContactGeometry, ContactTable, cached_table, normal_force
from conformal.dynamics.creep import CreepEvaluator, make_creep_model
from conformal.dynamics.scene import Irregularity, VehicleScene
from conformal.errors import ConvergenceError, InputError

SIDES = ("right", "left")
SIGN = np.array([1.0, 1.0, -1.0, -1.0])           # contacts: right tread, right flange, left tread, left flange
WHEEL = np.array([0, 0, 1, 1])


def alignment(irr: Irregularity, x: float) -> tuple[float, float]:
    """Lateral deviation (mm, towards the rail's field side) and its slope d/dx (mm/m) at x (m).

    One full cosine wave: amplitude/2 (1 - cos(2 pi (x - start)/wavelength)) on
    start <= x <= start + wavelength, zero elsewhere (value and slope continuous at both ends).

    >>> irr = Irregularity(amplitude=7.62, wavelength=11887.2, start=5.0)
    >>> round(alignment(irr, 5.0 + 11.8872 / 2)[0], 6), alignment(irr, 1.0)
    (7.62, (0.0, 0.0))
    """
    if irr.amplitude == 0.0:
        return 0.0, 0.0
    Lw = irr.wavelength / 1000.0
    u = x - irr.start
    if u <= 0.0 or u >= Lw:
        return 0.0, 0.0
    k = 2.0 * math.pi / Lw
    return 0.5 * irr.amplitude * (1.0 - math.cos(k * u)), 0.5 * irr.amplitude * k * math.sin(k * u)


@dataclass(frozen=True, eq=False)
class WheelsetModel:
    """All constants of the equations of motion (frozen); see the module docstring."""

    m: float
    Ixx: float
    Iyy: float
    Izz: float
    W: float
    kx: float
    ky: float
    cx: float
    cy: float
    b: float                 # half spacing of the longitudinal springs (m)
    V: float                 # m/s
    r0: float                # rolling radius at centred running (m)
    damping: float           # Eq. 57's C, N s/mm^2
    mu: float
    G: float
    nu: float
    table: ContactTable
    creep: CreepEvaluator
    creep_name: str
    irregularity: Irregularity

    @property
    def omega(self) -> float:
        """Spin rate about the axle (rad/s): pure rolling at r0."""
        return -self.V / self.r0

    # ------------------------------------------------------------------ contact kinematics
    def _deltas(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Alignment (mm, track y) and its rate (mm/s) of the right and left rails."""
        d, dd = np.zeros(2), np.zeros(2)
        irr = self.irregularity
        if irr.amplitude != 0.0:
            dev, slope = alignment(irr, self.V * t)
            k = 0 if irr.rail == "right" else 1
            sgn = 1.0 if k == 0 else -1.0          # towards that rail's field side
            d[k], dd[k] = sgn * dev, sgn * slope * self.V
        return d, dd

    def contacts(self, t: float, X: np.ndarray, with_creep: bool = True) -> dict:
        """Everything about the four patches (right/left x tread/flange) at state X."""
        y, z, phi, psi, yd, zd, phid, psid = X
        Y, Zw, Yd, Zd = 1000.0 * y, 1000.0 * z, 1000.0 * yd, 1000.0 * zd
        R0 = 1000.0 * self.r0
        dlt, ddlt = self._deltas(t)
        s2 = np.array([1.0, -1.0])
        y0 = s2 * (Y - dlt)                                   # per wheel, without roll
        yr = y0 - s2 * R0 * phi
        val, der = self.table.evaluate(np.concatenate([yr, y0]))
        vr, dr = val[:2].reshape(4, -1), der[:2].reshape(4, -1)      # at y_r, contacts in SIGN order
        v0, d0 = val[2:].reshape(4, -1), der[2:].reshape(4, -1)      # at y0
        s = SIGN
        Dd = ddlt[WHEEL]
        L0, dL0 = v0[:, C["L"]], d0[:, C["L"]]
        nz, dnz = vr[:, C["nz"]], dr[:, C["nz"]]
        Zc, dZc = vr[:, C["Z"]], dr[:, C["Z"]]
        K, dK = vr[:, C["Kh"]], dr[:, C["Kh"]]
        zeta = Zw + s * L0 * phi
        g = zeta - Zc
        p = nz * g                                            # Eq. 56 (overlap > 0)
        dp_dyr = dnz * g - nz * dZc
        dp_dY = s * dp_dyr + nz * phi * dL0
        dp_dZ = nz
        dp_dphi = -s * R0 * dp_dyr + nz * s * L0
        dp_dt = -s * Dd * dp_dyr - nz * phi * dL0 * Dd
        pdot = dp_dY * Yd + dp_dZ * Zd + dp_dphi * phid + dp_dt
        FN = normal_force(K, p, pdot, self.damping)            # Eq. 57
        pp = np.maximum(p, 0.0)
        extra = 0.4 * dK * pp * pp * np.sqrt(pp)              # d(Kh)/dy_r part of the energy gradient
        QY = -(FN * dp_dY + extra * s)
        QZ = -(FN * dp_dZ)
        Qphi = -(FN * dp_dphi - extra * s * R0) / 1000.0      # N m
        out = dict(p=p, pdot=pdot, FN=FN, QY=QY, QZ=QZ, Qphi=Qphi, yr=yr, vr=vr,
                   U=0.4 * K * pp * pp * np.sqrt(pp) / 1000.0)
        # ------------------------------------------------ creepages (Eqs. 58-61) and creep forces
        cph, sph, cps, sps = math.cos(phi), math.sin(phi), math.cos(psi), math.sin(psi)
        Rot = np.array([[cps, -sps, 0.0], [cph * sps, cph * cps, -sph], [sph * sps, sph * cps, cph]])
        a_axle = Rot[:, 1]
        omega = self.omega * a_axle + np.array([phid, 0.0, psid])         # Eq. 59
        Lr, Rr = vr[:, C["L"]] / 1000.0, vr[:, C["R"]] / 1000.0
        u = (Rot @ np.stack([np.zeros(4), s * Lr, Rr]))                    # (3, 4) contact points, m
        o0, o1, o2 = omega
        v = np.stack([self.V + o1 * u[2] - o2 * u[1], yd + o2 * u[0] - o0 * u[2],
                      zd + o0 * u[1] - o1 * u[0]])                         # Eqs. 58, 60: R' + w x u
        ny_t = s * vr[:, C["ny"]]
        nrm = np.hypot(ny_t, nz)
        n = np.stack([np.zeros(4), ny_t / nrm, nz / nrm])                 # inner rail normal, track frame
        t2 = np.stack([np.zeros(4), n[2], -n[1]])                          # t2 = n x t1, t1 = e_x
        Vs = self.V if self.V > 0 else 1.0
        xi = v[0] / Vs                                                     # Eq. 61
        eta = (v * t2).sum(axis=0) / Vs
        # Eq. 61 with n the inner rail normal (the seed's n^r is the outer one: opposite spin sign)
        spin = (omega @ n) / Vs / 1000.0                                   # rad/mm
        sq = np.sqrt(pp)
        a_ax, b_ax = vr[:, C["a1"]] * sq, vr[:, C["b1"]] * sq
        FX = np.zeros(4)
        FY = np.zeros(4)
        MZ = np.zeros(4)
        on = (FN > 0) & (pp > 0)
        if with_creep and on.any() and self.creep_name != "none":
            coeffs = vr[on][:, [C["c11"], C["c22"], C["c23"], C["c33"]]]
            FX[on], FY[on], MZ[on] = self.creep(a_ax[on], b_ax[on], FN[on], xi[on], eta[on], spin[on], coeffs)
        f = FY[None, :] * t2                                                        # on the wheel (N)
        f[0] += FX
        M = np.stack([u[1] * f[2] - u[2] * f[1], u[2] * f[0] - u[0] * f[2],
                      u[0] * f[1] - u[1] * f[0]]) + (MZ / 1000.0)[None, :] * n    # u x f + MZ n, N m
        out.update(xi=xi, eta=eta, spin=spin, a=a_ax, b=b_ax, FX=FX, FY=FY, MZ=MZ, f=f, M=M, n=n, u=u)
        return out

    # ------------------------------------------------------------------ equations of motion
    def rhs(self, t: float, X: np.ndarray) -> np.ndarray:
        """dX/dt of the state X = (y, z, phi, psi, y', z', phi', psi'); NaN where a wheel is
        outside the contact table (an adaptive integrator then rejects the trial step)."""
        try:
            c = self.contacts(t, X)
        except ConvergenceError:
            return np.full(8, np.nan)
        y, z, phi, psi, yd, zd, phid, psid = X
        f, M = c["f"], c["M"]
        QY = c["QY"].sum() + f[1].sum() - 2.0 * self.ky * y - 2.0 * self.cy * yd
        QZ = c["QZ"].sum() + f[2].sum() + 2.0 * self.W
        Qphi = c["Qphi"].sum() + M[0].sum() + self.Iyy * self.omega * psid           # gyroscopic
        Qpsi = M[2].sum() - 2.0 * self.kx * self.b**2 * psi - 2.0 * self.cx * self.b**2 * psid \
            - self.Iyy * self.omega * phid                                          # gyroscopic
        return np.array([yd, zd, phid, psid, QY / self.m, QZ / self.m, Qphi / self.Ixx, Qpsi / self.Izz])

    def energy(self, t: float, X: np.ndarray) -> float:
        """Kinetic + spring + contact (Hertz) energy - work potential of the loads (J); constant
        in time without creep forces, dampers and irregularity."""
        y, z, phi, psi, yd, zd, phid, psid = X
        c = self.contacts(t, X, with_creep=False)
        return (0.5 * self.m * (yd * yd + zd * zd) + 0.5 * self.Ixx * phid**2 + 0.5 * self.Izz * psid**2
                + self.ky * y * y + self.kx * self.b**2 * psi * psi + float(c["U"].sum()) - 2.0 * self.W * z)

    def outputs(self, t: float, X: np.ndarray) -> dict:
        """One row of the history: t, y (mm), yaw (rad) and per wheel the tread patch's creepages
        (xi, eta, phi in rad/mm), semi-axes a, b (mm) and normal force FN (N), the flange patch's
        FN_flange, the total force of the wheel on the rail FX, FY, FZ (N, track frame, z down),
        and the tread contact's position y_contact on the rail profile (mm)."""
        c = self.contacts(t, X)
        row = {"t": float(t), "y": 1000.0 * float(X[0]), "yaw": float(X[3]), "z": 1000.0 * float(X[1]),
               "roll": float(X[2])}
        for w, side in enumerate(SIDES):
            i, j = 2 * w, 2 * w + 1
            F = (c["FN"][[i, j]][None, :] * c["n"][:, [i, j]] - c["f"][:, [i, j]]).sum(axis=1)
            row.update({f"{side}_xi": c["xi"][i], f"{side}_eta": c["eta"][i], f"{side}_phi": c["spin"][i],
                        f"{side}_a": c["a"][i], f"{side}_b": c["b"][i], f"{side}_FN": c["FN"][i],
                        f"{side}_FX": F[0], f"{side}_FY": F[1], f"{side}_FZ": F[2],
                        f"{side}_y_contact": c["vr"][i, C["yc"]], f"{side}_FN_flange": c["FN"][j]})
        return {k: float(v) for k, v in row.items()}


#: the largest static overlap (mm) of a wheel on its rail; the seed's wheelset: 0.065 mm
MAX_STATIC_OVERLAP = 10.0


def build_model(scene: VehicleScene, *, table: ContactTable | None = None, table_step: float | None = None,
                table_range: float | None = None) -> WheelsetModel:
    """The equations of motion of a vehicle scene.

    Parameters
    ----------
    scene : VehicleScene
    table : ContactTable, optional
        A contact table to use; by default it is built from the scene's profiles (about 10 ms
        per grid point) or taken from the in-memory cache.
    table_step, table_range : float, optional
        Override ``[contact] table_step`` and ``table_range`` (mm).

    Returns
    -------
    WheelsetModel
        With :meth:`WheelsetModel.rhs`, :meth:`WheelsetModel.energy` and :meth:`WheelsetModel.outputs`.

    Examples
    --------
    See the module docstring.
    """
    v, tr, wh, ct = scene.vehicle, scene.track, scene.wheels, scene.contact
    geom = ContactGeometry(wh.wheel_profile, tr.rail_profile, tr.rail_cant, tr.gauge, tr.gauge_height,
                           wh.wheel_radius, wh.flange_back, wh.flange_back_pos, scene.material, scene.base_dir)
    mat = scene.material
    opts = {"n": ct.fastsim_n} if ct.creep_model == "fastsim" else {}
    if ct.creep_model == "table":
        opts = {"table": ct.table}
    creep = make_creep_model(ct.creep_model, mu=ct.mu, G=mat.G, nu=mat.nu, **opts)
    if table is None:
        table = cached_table(geom, table_step or ct.table_step, table_range or ct.table_range)
    val, _ = table.evaluate(np.array([0.0]))
    r0 = float(val[0, 0, C["R"]]) / 1000.0
    return WheelsetModel(m=v.mass, Ixx=v.Ixx, Iyy=v.Iyy, Izz=v.Izz, W=v.wheel_load, kx=v.kx, ky=v.ky, cx=v.cx,
                         cy=v.cy, b=0.5 * v.spring_spacing, V=scene.simulation.speed, r0=r0,
                         damping=ct.damping, mu=ct.mu, G=mat.G, nu=mat.nu, table=table, creep=creep,
                         creep_name=ct.creep_model, irregularity=tr.irregularity)


def equilibrium(model: WheelsetModel, y: float = 0.0, psi: float = 0.0, t: float = 0.0) -> np.ndarray:
    """State at rest in the vertical and roll directions (vertical force and roll moment of the
    normal contact forces balance the loads) for the lateral position y (m) and yaw psi."""
    val, _ = model.table.evaluate(np.array([1000.0 * y, -1000.0 * y]))
    ZR, ZL = val[0, 0, C["Z"]], val[1, 0, C["Z"]]
    Kh = float(val[0, 0, C["Kh"]])
    overlap = (model.W / Kh) ** (2.0 / 3.0)                           # mm, Hertz: W = Kh overlap^(3/2)
    if not overlap <= MAX_STATIC_OVERLAP:       # wheel_load = 1e300: the contact leaves the float range
        raise InputError(f"[vehicle] wheel_load: {model.W:g} N presses each wheel {overlap:.3g} mm into its rail "
                         f"(Hertz), more than {MAX_STATIC_OVERLAP:g} mm: far beyond elastic contact (the seed's "
                         "wheelset: 0.065 mm)")
    z0 = 0.5 * (ZR + ZL) + overlap
    phi0 = 1000.0 * (ZR - ZL) / (2.0 * val[0, 0, C["L"]])             # mrad

    def state(q):
        return np.array([y, q[0] / 1000.0, q[1] / 1000.0, psi, 0.0, 0.0, 0.0, 0.0])

    def res(q):
        c = model.contacts(t, state(q), with_creep=False)
        return [(c["QZ"].sum() + 2.0 * model.W) / model.W, c["Qphi"].sum() / model.W]

    q, info, ier, msg = fsolve(res, [z0, phi0], full_output=True, xtol=1e-13)
    if ier != 1 and max(abs(v) for v in res(q)) > 1e-9:
        raise ConvergenceError(f"wheelset dynamics: no static equilibrium at y = {1000 * y:.2f} mm ({msg})")
    return state(q)
