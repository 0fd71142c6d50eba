"""Initial conditions on the paper's conical relative equilibrium (Sec. 5.1, 5.1.6).

A body whose dipole lies on its symmetry axis, in a field rotating at ``omega`` about z with
cyclic and static torque coefficients ``tau_C = |m| B_C`` and ``tau_S = |m| B_S``, can turn
on a cone of zenith angle ``phi`` synchronised with the field (Eq. 5.7, 5.20). These helpers
give ``phi`` (Eq. 5.24 isotropic, Eq. 5.35 axisymmetric, Eq. 5.64/5.68 with spin ``k``) and
the matching initial orientation and angular velocity (Eq. 5.12, 5.62).

:mod:`labkit.model.cone` has vectorised versions of the same closed forms. They are kept
apart on purpose: its Eq. 5.35/5.64 solver is a Newton iteration returning NaN, this one
brackets the root next to the isotropic guess and raises, and the two can pick different
roots of the same equation; the isotropic and angular-velocity forms agree only to rounding.
Scenes must keep their exact initial conditions, so the simulator uses these.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from labkit.sim.rotations import euler_zxz, rot_x

if TYPE_CHECKING:  # pragma: no cover
    from labkit.sim.scene import Scene, SceneBody

MU0_OVER_4PI = 1e-7  # T m / A (paper, below Eq. 4.3)


def cone_angle_isotropic(
    *, omega: float, tau_c: float, tau_s: float, inertia: float, spin_k: float = -1.0
) -> float:
    """Cone angle (rad) for equal principal moments: Eq. 5.24 (``k = -1``), Eq. 5.68 otherwise.

    Keyword-only, like every cone function here: :func:`labkit.model.cone.cone_angle` takes the
    same quantities in another order (docs/decisions/0007-names.md).

    ``phi = atan(tau_C / (-k I omega^2 - tau_S))``; its sign flips when ``tau_S > I omega^2``.
    """
    den = -spin_k * inertia * omega**2 - tau_s
    if den == 0.0:
        return math.copysign(math.pi / 2.0, tau_c)
    return math.atan(tau_c / den)


def cone_angle_axisymmetric(
    *, omega: float, tau_c: float, tau_s: float, i_radial: float, i_axial: float, spin_k: float = -1.0
) -> float:
    """Cone angle (rad) solving ``tau_C cos phi + tau_S sin phi = omega^2 sin phi (-k I_A +
    (I_R - I_A) cos phi)`` (Eq. 5.64; Eq. 5.35 for ``k = -1``), nearest the isotropic guess."""

    def f(phi: float) -> float:
        s, c = math.sin(phi), math.cos(phi)
        return tau_c * c + tau_s * s - omega**2 * s * (-spin_k * i_axial + (i_radial - i_axial) * c)

    guess = cone_angle_isotropic(omega=omega, tau_c=tau_c, tau_s=tau_s,
                                 inertia=0.5 * (i_radial + i_axial), spin_k=spin_k)
    if i_radial == i_axial:
        return guess
    from scipy.optimize import brentq  # only anisotropic bodies need a root finder

    lo, hi = -math.pi / 2 + 1e-12, math.pi / 2 - 1e-12
    for width in (0.05, 0.2, 0.5, 1.0, math.pi):
        a, b = max(lo, guess - width), min(hi, guess + width)
        if f(a) * f(b) <= 0.0:
            return brentq(f, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    raise ValueError("no conical equilibrium angle exists for these torques and inertia (Eq. 5.35)")


def conical_angular_velocity_at(
    *, omega: float, phi: float, theta: float, spin_k: float = -1.0
) -> np.ndarray:
    """Lab angular velocity on the cone (Eq. 5.62; Eq. 5.12 for ``k = -1``) at azimuth ``theta``
    (one point; :func:`labkit.model.cone.conical_angular_velocity` is the vectorised one, in time)."""
    s, c = math.sin(theta), math.cos(theta)
    sp, cp = math.sin(phi), math.cos(phi)
    return omega * np.array([spin_k * s * sp, -spin_k * c * sp, 1.0 + spin_k * cp])


def conical_orientation(phi: float, theta: float) -> np.ndarray:
    """Body -> lab rotation on the cone, ``R_E(theta, phi, -theta)`` (Eq. 5.6-5.7)."""
    return euler_zxz(theta, phi, -theta)


def dipole_torque_coefficients(
    m_rotator: float, m_floator: float, distance: float, tilt: float
) -> tuple[float, float]:
    """``(tau_C, tau_S)`` (N m) on a floator on the axis of a tilted rotating dipole (Eq. 5.28)."""
    big_m = MU0_OVER_4PI * m_rotator * m_floator / distance**3
    return big_m * math.cos(tilt), 2.0 * big_m * math.sin(tilt)


def _drive(body: SceneBody, scene: Scene) -> tuple[float, float, float, float]:
    """``(omega, phase, tau_C, tau_S)`` of the drive acting on ``body``."""
    m = float(np.linalg.norm(body.moment_Am2))
    if m == 0.0:
        raise ValueError("the conical equilibrium needs a body with a dipole moment")
    fld = scene.field
    if fld is not None and fld.kind == "rotating":
        return fld.omega_rad_s, fld.phase_rad, m * fld.B_c_T, m * fld.B_s_T
    if fld is None and len(scene.rotators) == 1:
        rot = scene.rotators[0]
        rel = body.position_m + body.rotation @ body.dipole_offset_m - rot.axis_point_m
        if math.hypot(rel[0], rel[1]) > 1e-12 * max(1.0, abs(rel[2])) or rel[2] == 0.0:
            raise ValueError("the conical equilibrium needs the body on the rotator's axis (x = y = 0)")
        tau_c, tau_s = dipole_torque_coefficients(rot.moment_Am2, m, abs(rel[2]), rot.tilt_rad)
        return rot.omega_rad_s, rot.phase_rad, tau_c, tau_s
    others = [o for o in scene.bodies if o is not body and float(np.linalg.norm(o.moment_Am2)) > 0]
    if fld is None and not scene.rotators and len(others) == 1:
        # a free spinning rotator body (Sec. 6.0.1): its spin about z drives the floator
        o = others[0]
        m_lab = o.rotation @ np.asarray(o.moment_Am2, dtype=float)
        m_r = float(np.linalg.norm(m_lab))
        tilt = math.asin(max(-1.0, min(1.0, m_lab[2] / m_r)))
        phase = math.atan2(m_lab[0], -m_lab[1])  # m_R = m [cos g sin th, -cos g cos th, sin g] (Eq. 5.25)
        rel = (
            body.position_m
            + body.rotation @ body.dipole_offset_m
            - (o.position_m + o.rotation @ o.dipole_offset_m)
        )
        if math.hypot(rel[0], rel[1]) > 1e-12 * max(1.0, abs(rel[2])) or rel[2] == 0.0:
            raise ValueError("the conical equilibrium needs the body on the rotator body's z axis")
        tau_c, tau_s = dipole_torque_coefficients(m_r, m, abs(rel[2]), tilt)
        return float(o.angular_velocity_rad_s[2]), phase, tau_c, tau_s
    raise ValueError(
        "the conical equilibrium needs one rotating uniform field, one rotator or one spinning body"
    )


def apply_conical(body: SceneBody, scene: Scene, spin_k: float = -1.0) -> float:
    """Set ``body``'s orientation and angular velocity on the conical equilibrium; return phi.

    The body must be axisymmetric about body z with its dipole on that axis (Eq. 5.33).
    """
    inertia = np.asarray(body.inertia_kg_m2, dtype=float)
    m = np.asarray(body.moment_Am2, dtype=float)
    off_diag = inertia - np.diag(np.diag(inertia))
    if (
        np.any(np.abs(off_diag) > 1e-12 * np.max(np.abs(inertia)))
        or not math.isclose(inertia[0, 0], inertia[1, 1], rel_tol=1e-12)
        or np.linalg.norm(m[:2]) > 1e-12 * np.linalg.norm(m)
    ):
        raise ValueError(
            "the conical equilibrium needs an axisymmetric body (I_xx = I_yy) "
            "with its dipole on body z (Eq. 5.33)"
        )
    omega, phase, tau_c, tau_s = _drive(body, scene)
    phi = cone_angle_axisymmetric(omega=omega, tau_c=tau_c, tau_s=tau_s, i_radial=inertia[0, 0],
                                  i_axial=inertia[2, 2], spin_k=spin_k)
    rotation = conical_orientation(phi, phase)
    if m[2] < 0:  # dipole along -z: flip the body so that its dipole is on the cone
        rotation = rotation @ rot_x(math.pi)
    body.rotation = rotation
    body.angular_velocity_rad_s = conical_angular_velocity_at(
        omega=omega, phi=phi, theta=phase, spin_k=spin_k)
    body.spin_k = spin_k
    return phi
