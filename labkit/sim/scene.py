"""Scenes: what is simulated (bodies, drives, fields, gravity, damping, initial conditions).

A scene is plain data, described in TOML (``load_scene``, :mod:`labkit.sim.scene_file`) or built
in Python from the dataclasses below (``Scene(...)`` then ``validate_scene``,
:mod:`labkit.sim.scene_checks`). Every quantity is SI inside;
TOML keys carry their unit (``mass_g`` or ``mass_kg``, ``speed_rpm`` or ``omega_rad_s``), and
giving one quantity in two units, an unknown key, a zero mass, a non-positive-definite inertia
or overlapping bodies ends with :class:`SceneError` (``file:key: reason``).

Conventions (paper Sec. 5.1-5.2):

* uniform rotating field ``B = B_C [-sin th, cos th, 0] + B_S z``, ``th = omega t + phase``
  (Eq. 5.21); an oscillating field is ``B = B_C cos(th) y + B_S z`` (Eq. 5.481);
* a driven rotator is a point dipole spinning about the lab z axis through ``axis_point``:
  ``m_R = m [cos g sin th, -cos g cos th, sin g]`` with tilt ``g`` (Eq. 5.25), optionally
  shifted from the axis by ``shift`` (a vector in the rotator's frame, rotating with it);
* body orientation ``R`` maps body to lab; a body's dipole is ``R m_body`` at ``x + R offset``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from labkit.errors import RigFileError


class SceneError(RigFileError):
    """A scene is wrong. Formats as ``file:key: reason`` (``file: reason`` without a key)."""

    def __init__(self, file: str, key: str, reason: str) -> None:
        super().__init__(file, key, reason)
        if not key:
            self.args = (f"{self.file}: {reason}",)

    def __str__(self) -> str:
        return str(self.args[0])


@dataclass
class Shape:
    """Shape used for contact only: a sphere of ``radius_m`` or a cylinder (radius, height).

    Contact is tested against the bounding sphere (cylinder: half its diagonal), which is
    conservative: a reported contact may be a near miss by up to the shape's corner gap.
    """

    kind: str = "point"
    radius_m: float = 0.0
    height_m: float = 0.0

    @property
    def contact_radius_m(self) -> float:
        if self.kind == "cylinder":
            return math.hypot(self.radius_m, 0.5 * self.height_m)
        return self.radius_m


@dataclass
class SceneBody:
    """A rigid body with a point dipole, placed in a simulated scene (not
    :class:`labkit.rig.BodySpec`, a magnet as a rig file declares it). ``inertia_kg_m2`` is
    the 3x3 tensor about the CM in
    the body frame; ``moment_Am2`` the dipole vector in the body frame (default along body z);
    ``rotation`` maps body to lab; ``angular_velocity_rad_s`` is in the lab frame."""

    name: str
    mass_kg: float
    inertia_kg_m2: np.ndarray
    moment_Am2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    dipole_offset_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    shape: Shape = field(default_factory=Shape)
    pinned: bool = False
    damping_N_s_m: float = 0.0
    damping_rot_N_m_s: float = 0.0
    position_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    velocity_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    angular_velocity_rad_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    spin_k: float = -1.0  # spin parameter of Eq. 5.62 (-1: no spin), set by the conical helper


@dataclass
class Rotator:
    """A driven dipole on the lab z axis through ``axis_point_m``: not integrated, its angle is
    ``phase + omega t + ramp t^2 / 2`` (Eq. 5.25 with tilt ``tilt_rad``)."""

    name: str
    moment_Am2: float
    omega_rad_s: float
    tilt_rad: float = 0.0
    phase_rad: float = 0.0
    ramp_rad_s2: float = 0.0
    shift_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis_point_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    contact_radius_m: float = 0.0


@dataclass
class UniformField:
    """Uniform field: ``rotating`` (Eq. 5.21), ``oscillating`` (Eq. 5.481) or ``static``."""

    kind: str = "rotating"
    B_c_T: float = 0.0
    B_s_T: float = 0.0
    omega_rad_s: float = 0.0
    phase_rad: float = 0.0


@dataclass
class Scene:
    name: str
    bodies: list[SceneBody]
    rotators: list[Rotator] = field(default_factory=list)
    field: UniformField | None = None
    gravity_m_s2: np.ndarray | None = None
    escape_radius_m: float | None = None
    period_s: float | None = None
    cycles: int = 100
    description: str = ""
    source: str = "<scene>"

    def drive_omega(self) -> float:
        """The drive's angular speed (rad/s) that sets the period and the step (h = T/N)."""
        if self.field is not None and self.field.kind != "static" and self.field.omega_rad_s:
            return abs(self.field.omega_rad_s)
        if self.rotators:
            return max(abs(r.omega_rad_s) for r in self.rotators)
        if self.period_s:
            return 2.0 * math.pi / self.period_s
        spins = [float(np.linalg.norm(b.angular_velocity_rad_s)) for b in self.bodies]
        return max(spins) if spins and max(spins) > 0 else 0.0

    def period(self) -> float:
        """Drive period T (s); raises if the scene has no drive, spin or ``period_s``."""
        if self.period_s:
            return float(self.period_s)
        w = self.drive_omega()
        if w <= 0:
            raise SceneError(self.source, "scene.period_s", "no drive, field or spin sets a period: give one")
        return 2.0 * math.pi / w


#: the old name of :class:`SceneBody` (docs/decisions/0007-names.md); kept for scripts
Body = SceneBody
