"""Interior (3-D) elastic field of ONE half-space under a uniform traction on a rectangle.

(Moved here from conformal.influence.fe_halfspace3d, which re-exports it: the subsurface stresses
of conformal.stresses superpose these fields, Love 1929 / Boussinesq-Cerruti.)

The FE influence numbers (:mod:`conformal.influence.fe`) split the displacement of a body into
the analytic half-space field of the loaded element and a smooth FE correction (docs/architecture.md §5,
"subtract the analytic singular part").  The FE correction needs the half-space field inside the
body (Dirichlet data on the clamped faces) and its stress on the free surface (the residual
traction of a curved surface), so this module gives displacement and stress at any point with
z >= 0, not only on the surface.

Frame: the body fills z > 0 (z points into the body); the loaded rectangle is
[-dx/2, dx/2] x [-dy/2, dy/2] on z = 0; a unit uniform traction p_j (j = x, y, z) acts ON the body.
Results are indexed [..., component, load]: ``u[..., i, j]`` is u_i due to p_j, and
``sigma[..., k, l, j]`` the stress sigma_kl due to p_j.

Derivation (our own; verified numerically in tests/validation/test_fe_influence.py and against the surface
closed forms of conformal.influence.halfspace at z -> 0): the point-load fields of Boussinesq and
Cerruti (Johnson 1985, eqs. 3.19-3.22 in the form z into the body) are written as derivatives of
the potentials 1/rho, ln(rho + z), rho and Psi = z ln(rho + z) - rho.  Integrating over the
rectangle commutes with those derivatives, so every displacement component is a corner double
difference D[.] (reference halfspace_influence.md §3.1) of one of the corner primitives below.
Stresses follow from the displacement gradient by complex-step differentiation (exact to round-off
because every primitive is analytic off the loaded area).

Point-load fields (unit force at the origin, c0 = 1/(4 pi G), rho = |x|):
  Boussinesq F_z:  u_x = c0 [x z/rho^3 - (1-2nu) x/(rho(rho+z))],  u_z = c0 [z^2/rho^3 + 2(1-nu)/rho]
  Cerruti F_x:     u_x = c0 [1/rho + x^2/rho^3 + (1-2nu)(1/(rho+z) - x^2/(rho(rho+z)^2))]
                   u_y = c0 [x y/rho^3 - (1-2nu) x y/(rho(rho+z)^2)]
                   u_z = c0 [x z/rho^3 + (1-2nu) x/(rho(rho+z))]
At z = 0 they reduce to the surface kernels of the reference (§2.1).

>>> import numpy as np
>>> u = rectangle_displacement(np.array([[0.0, 0.0, 1e-12]]), 1.0, 1.0, G=1.0, nu=0.28)
>>> round(float(u[0, 2, 2]), 9)   # single body: half the two-body A_zz(0,0) = 0.8079837873684 / 2
0.403991894
"""
from __future__ import annotations

import math

import numpy as np

from conformal.materials import lame_lambda

# corners of the loaded rectangle and their signs in the double difference D[.]
_CORNERS = ((0.5, 0.5, 1.0), (0.5, -0.5, -1.0), (-0.5, 0.5, -1.0), (-0.5, -0.5, 1.0))
_TINY = 1e-300


def _corner_terms(a, b, z):
    """Corner primitives at (a, b, z); a = x - xi, b = y - eta of a rectangle corner (xi, eta).

    Returns the ten primitives used by the displacement formulas.  Written with sqrt, log, asinh
    and atan only (no abs, no branches), so that complex arguments give complex-step derivatives.
    """
    a2, b2, z2 = a * a, b * b, z * z
    rho = np.sqrt(a2 + b2 + z2)
    rz = rho + z
    ca = np.sqrt(a2 + z2)
    cb = np.sqrt(b2 + z2)
    Sb = np.arcsinh(b / ca)                       # P_b(1/rho)
    Sa = np.arcsinh(a / cb)                       # P_a(1/rho)
    r2 = a2 + b2
    # atan(b/a) - atan(z b/(a rho)) in one smooth atan (valid: the product of the two is >= 0)
    Tb = np.arctan(a * b * r2 / (rz * (a2 * rho + z * b2) + _TINY))
    Ta = np.arctan(a * b * r2 / (rz * (b2 * rho + z * a2) + _TINY))
    atn = np.arctan(a * b / (z * rho))
    lrz = np.log(rz)
    Pab = a * Sb + b * Sa - z * atn               # P_ab(1/rho): Love's primitive, z > 0
    Pb_ln = b * lrz - b + z * Sb + a * Tb         # P_b(ln(rho + z))
    Pa_ln = a * lrz - a + z * Sa + b * Ta
    aPb = a * Sb - z * Tb                         # a P_b(1/(rho + z))
    bPa = b * Sa - z * Ta
    psi = z * lrz - rho                           # Psi
    return Sb, Sa, atn, Pab, Pb_ln, Pa_ln, aPb, bPa, psi, rho, a * Sb, b * Sa


def _displacement_local(x, y, z, dx, dy, G, nu):
    """u[..., i, j] for arrays x, y, z (may be complex for complex-step)."""
    c0 = 1.0 / (4.0 * math.pi * G)
    acc = None
    for fx, fy, sign in _CORNERS:
        t = _corner_terms(x - fx * dx, y - fy * dy, z)
        acc = [sign * v for v in t] if acc is None else [s + sign * v for s, v in zip(acc, t)]
    DSb, DSa, Datn, DPab, DPb_ln, DPa_ln, DaPb, DbPa, Dpsi, Drho, DaSb, DbSa = acc
    k = 1.0 - 2.0 * nu
    shape = np.broadcast(x, y, z).shape
    u = np.empty(shape + (3, 3), dtype=np.result_type(x, y, z, float))
    # normal load p_z
    u[..., 0, 2] = c0 * (-z * DSb - k * DPb_ln)
    u[..., 1, 2] = c0 * (-z * DSa - k * DPa_ln)
    u[..., 2, 2] = c0 * (z * Datn + 2.0 * (1.0 - nu) * DPab)
    # tangential load p_x
    u[..., 0, 0] = c0 * (2.0 * DPab - DaSb + k * DaPb)
    u[..., 1, 0] = c0 * (-Drho - k * Dpsi)
    u[..., 2, 0] = c0 * (-z * DSb + k * DPb_ln)
    # tangential load p_y
    u[..., 1, 1] = c0 * (2.0 * DPab - DbSa + k * DbPa)
    u[..., 0, 1] = u[..., 1, 0]
    u[..., 2, 1] = c0 * (-z * DSa + k * DPa_ln)
    return u


def _point_displacement_local(x, y, z, G, nu):
    """Unit point forces at the origin (Boussinesq, Cerruti): u[..., i, j]."""
    c0 = 1.0 / (4.0 * math.pi * G)
    k = 1.0 - 2.0 * nu
    rho = np.sqrt(x * x + y * y + z * z)
    rz = rho + z
    r3 = rho ** 3
    shape = np.broadcast(x, y, z).shape
    u = np.empty(shape + (3, 3), dtype=np.result_type(x, y, z, float))
    u[..., 0, 2] = c0 * (x * z / r3 - k * x / (rho * rz))
    u[..., 1, 2] = c0 * (y * z / r3 - k * y / (rho * rz))
    u[..., 2, 2] = c0 * (z * z / r3 + 2.0 * (1.0 - nu) / rho)
    u[..., 0, 0] = c0 * (1.0 / rho + x * x / r3 + k * (1.0 / rz - x * x / (rho * rz * rz)))
    u[..., 1, 0] = c0 * (x * y / r3 - k * x * y / (rho * rz * rz))
    u[..., 2, 0] = c0 * (x * z / r3 + k * x / (rho * rz))
    u[..., 1, 1] = c0 * (1.0 / rho + y * y / r3 + k * (1.0 / rz - y * y / (rho * rz * rz)))
    u[..., 0, 1] = u[..., 1, 0]
    u[..., 2, 1] = c0 * (y * z / r3 + k * y / (rho * rz))
    return u


def _point_stress_local(x, y, z, nu):
    """Stress sigma[..., k, l, j] of unit point forces F_j at the origin (Boussinesq, Cerruti).

    Generated with sympy from :func:`_point_displacement_local` (strain -> Hooke, common
    subexpressions eliminated); checked against the complex-step derivative in the tests.
    """
    x0 = x**2
    x1 = y**2
    x2 = z**2
    x3 = x0 + x1 + x2
    x4 = x3**(-5/2)
    x5 = 3*x4
    x6 = x0*x5
    x7 = np.sqrt(x3)
    x8 = 1/x7
    x9 = -3*x8
    x10 = x3**(-3/2)
    x11 = x0*x10
    x12 = x7 + z
    x13 = 1/x12
    x14 = 1/x3
    x15 = 2*x14
    x16 = x13*x15
    x17 = x0*x16 + x11
    x18 = x12**(-2)
    x19 = 2*nu - 1
    x20 = x18*x19
    x21 = x20*(x17 + x9)
    x22 = x1*x5
    x23 = x20*x8
    x24 = -x23
    x25 = x1*x10
    x26 = x20*x25
    x27 = x19/x12**3
    x28 = x15*x27
    x29 = x1*x28
    x30 = x24 + x26 + x29
    x31 = x2*x5
    x32 = x10*z
    x33 = x13*x19
    x34 = x32*x33
    x35 = x8*z
    x36 = x35 + 1
    x37 = x23*x36
    x38 = -3*x10 + x31 - x34 - x37
    x39 = nu/x19
    x40 = x10 + x39*(x21 + x22 + x30 + x38 + x6)
    x41 = 2*x
    x42 = -x31 + x34 + x37
    x43 = 6*x4
    x44 = x0*x43
    x45 = -x8
    x46 = x0*x28 + x11*x20 + x24
    x47 = 2*x36*x8
    x48 = x13*x47
    x49 = -x35 - 1
    x50 = x33*x8
    x51 = x11*x33
    x52 = x14*x20
    x53 = x0*x52
    x54 = x50 - x51 - x53
    x55 = x43*z
    x56 = x*y*(x10*x13*x19 + x14*x18*x19 - x20*x32 - x27*x47 - x55)
    x57 = x1*x16 + x25
    x58 = x20*(x57 + x9) + x22
    x59 = x46 + x6
    x60 = x38 + x58 + x59
    x61 = -x10 - x39*x60
    x62 = 2*y
    x63 = x25*x33
    x64 = x1*x52
    x65 = x50 - x63 - x64
    x66 = x6*z
    x67 = x5*z**3
    x68 = x22*z
    x69 = nu - 1
    x70 = 2*x32
    x71 = x69*x70
    x72 = x39*(-4*x32 - 2*x50 + x51 + x53 + x63 + x64 + x66 + x67 + x68 - x71)
    x73 = x32 + x72
    x74 = x8*(-x14*x33*z + 2*x14*x69 + x14 - 6*x2/x3**2 - x20*x36)
    s00_0 = x41*(-x21 + x40 - x6)
    s11_0 = x41*(-x22 + x23 - x26 - x29 + x40)
    s22_0 = x41*(x40 + x42)
    s01_0 = y*(-x20*(x17 + x45) - x44 - x46)
    s02_0 = -x20*(x0*x48 + x11*z + x49) - x44*z - x54
    s12_0 = x56
    s00_1 = x62*(-x59 - x61)
    s11_1 = x62*(-x58 - x61)
    s22_1 = x62*(x10 + x39*x60 + x42)
    s01_1 = x*(-x1*x43 - x20*(x45 + x57) - x30)
    s02_1 = x56
    s12_1 = -x1*x55 - x20*(x1*x48 + x25*z + x49) - x65
    s00_2 = 2*x54 - 2*x66 + 2*x73
    s11_2 = 2*x65 - 2*x68 + 2*x73
    s22_2 = -2*x67 + 2*x70 + 2*x71 + 2*x72
    s01_2 = -x41*y*(x10*x33 + x5*z + x52)
    s02_2 = x*x74
    s12_2 = x74*y
    out = np.empty(np.broadcast(x, y, z).shape + (3, 3, 3))
    for j, comps in enumerate(((s00_0, s11_0, s22_0, s01_0, s02_0, s12_0),
                               (s00_1, s11_1, s22_1, s01_1, s02_1, s12_1),
                               (s00_2, s11_2, s22_2, s01_2, s02_2, s12_2))):
        for (a, b), v in zip(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)), comps):
            out[..., a, b, j] = v
            out[..., b, a, j] = v
    return out / (4.0 * math.pi)


def _gauss_rectangle_displacement(x, y, z, dx, dy, G, nu, ng):
    """The rectangle as ng x ng Gauss points carrying point forces (far field)."""
    g, w = np.polynomial.legendre.leggauss(ng)
    u = 0.0
    for gi, wi in zip(g, w):
        for gj, wj in zip(g, w):
            u = u + (0.25 * wi * wj * dx * dy) * _point_displacement_local(
                x - 0.5 * gi * dx, y - 0.5 * gj * dy, z, G, nu)
    return u


def _gauss_rectangle_stress(x, y, z, dx, dy, nu, ng):
    """Stress of the rectangle as ng x ng Gauss points carrying point forces (far field)."""
    g, w = np.polynomial.legendre.leggauss(ng)
    s = 0.0
    for gi, wi in zip(g, w):
        for gj, wj in zip(g, w):
            s = s + (0.25 * wi * wj * dx * dy) * _point_stress_local(x - 0.5 * gi * dx, y - 0.5 * gj * dy, z, nu)
    return s


def _split(points):
    p = np.asarray(points)
    return p[..., 0], p[..., 1], np.maximum(p[..., 2], 0.0) if not np.iscomplexobj(p) else p[..., 2]


def _near_mask(x, y, dx, dy, near):
    """Points within ``near`` element sizes of the rectangle centre (closed forms there)."""
    h = max(dx, dy)
    return (np.abs(x) <= near * h) & (np.abs(y) <= near * h)


def _evaluate(func_near, func_far, points, dx, dy, near):
    x, y, z = _split(points)
    z = np.where(z > 0.0, z, 1e-12 * min(dx, dy))  # closed forms need z > 0 (surface: z -> 0+)
    if near is None:
        return func_near(x, y, z)
    mask = _near_mask(x, y, dx, dy, near)
    out = np.empty(x.shape + (3, 3), dtype=float)
    if mask.any():
        out[mask] = func_near(x[mask], y[mask], z[mask])
    if (~mask).any():
        out[~mask] = func_far(x[~mask], y[~mask], z[~mask])
    return out


def rectangle_displacement(points, dx: float, dy: float, *, G: float, nu: float,
                           near: float | None = 4.0, ng: int = 3) -> np.ndarray:
    """Displacement u[..., i, j] at ``points`` (..., 3) (local frame, z >= 0) per unit traction p_j.

    ``near``: within ``near`` element sizes of the rectangle (in x and y) the closed form is used,
    beyond it an ng x ng Gauss rule of point forces (error about (h/r)^(2 ng) relative; ng = 3 at
    r = 4 h: 1e-6).  ``near=None`` uses the closed form everywhere.
    """
    return _evaluate(lambda x, y, z: _displacement_local(x, y, z, dx, dy, G, nu),
                     lambda x, y, z: _gauss_rectangle_displacement(x, y, z, dx, dy, G, nu, ng),
                     points, dx, dy, near)


def _stress_from(func, x, y, z, G, nu, scale):
    """Stress sigma[..., k, l, j] of displacement func(x, y, z) -> u[..., i, j] by complex step."""
    h = 1e-20 * scale
    grad = np.empty(np.shape(x) + (3, 3, 3))  # [..., i, l, j] = d u_i / d x_l for load j
    for l, (ex, ey, ez) in enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1))):
        u = func(x + 1j * h * ex, y + 1j * h * ey, z + 1j * h * ez)
        grad[..., :, l, :] = u.imag / h
    eps = 0.5 * (grad + np.swapaxes(grad, -3, -2))
    lam = lame_lambda(G, nu)
    tr = eps[..., 0, 0, :] + eps[..., 1, 1, :] + eps[..., 2, 2, :]
    sigma = 2.0 * G * eps
    for k in range(3):
        sigma[..., k, k, :] += lam * tr
    return sigma


def rectangle_stress(points, dx: float, dy: float, *, G: float, nu: float,
                     near: float | None = 4.0, ng: int = 3) -> np.ndarray:
    """Stress sigma[..., k, l, j] at ``points`` (local frame, z > 0) per unit traction p_j.

    On the loaded area itself (z -> 0+) the traction sigma . (-e_z) equals p (the body's outward
    normal is -e_z); the in-plane stresses are log-singular at the rectangle's edges.
    """
    x, y, z = _split(points)
    z = np.where(z > 0.0, z, 1e-12 * min(dx, dy))
    scale = max(dx, dy)

    def near_fn(x, y, z):
        return _stress_from(lambda a, b, c: _displacement_local(a, b, c, dx, dy, G, nu), x, y, z, G, nu, scale)

    def far_fn(x, y, z):
        return _gauss_rectangle_stress(x, y, z, dx, dy, nu, ng)

    if near is None:
        return near_fn(x, y, z)
    mask = _near_mask(x, y, dx, dy, near)
    out = np.empty(x.shape + (3, 3, 3))
    if mask.any():
        out[mask] = near_fn(x[mask], y[mask], z[mask])
    if (~mask).any():
        out[~mask] = far_fn(x[~mask], y[~mask], z[~mask])
    return out


def point_displacement(points, *, G: float, nu: float) -> np.ndarray:
    """Boussinesq-Cerruti displacement u[..., i, j] of unit point forces at the origin."""
    p = np.asarray(points, dtype=float)
    return _point_displacement_local(p[..., 0], p[..., 1], p[..., 2], G, nu)
