"""Compile a scene to the smallest system it needs, and say what was kept and why.

* A uniform field exerts no force: translation is not integrated (the CM moves in closed form
  under gravity and damping).
* A pinned body has no translational degrees of freedom (its force is still evaluated for the
  cycle-averaged force, not applied).
* A driven rotator is not integrated: its angle is prescribed (Eq. 5.25).
* One isotropic body in an oscillating field with its dipole and spin in the plane of the
  field is exactly the one-DoF Eq. 5.484; in a rotating field without static part with its
  dipole in the plane and spin along z, it is the planar Eq. 5.56.
* Absent gravity, damping, uniform field, rotators and body pairs are not evaluated.
* Free rotation is exact for symmetric tops; three unequal moments use the DLM sequence.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from labkit.sim.integrators.kernels import (
    BF_WIDTH,
    F_DAMPING,
    F_FIELD,
    F_FORCES,
    F_GRAVITY,
    F_PAIRS,
    F_SOURCES,
    K_M,
    SRC_WIDTH,
)
from labkit.sim.scene import Scene, SceneBody


@dataclass
class ReducedForm:
    """A one-DoF reduced system ``y'' = f(y, t)`` (Eq. 5.484 form 0, Eq. 5.56 form 1)."""

    form: int
    jc: float
    js: float
    omega: float
    phase: float
    y0: float
    yd0: float
    inertia: float
    moment: float

    @property
    def equation(self) -> str:
        return "Eq. 5.484" if self.form == 0 else "Eq. 5.56"


@dataclass
class CompiledSystem:
    scene: Scene
    kind: str  # "rigid", "reduced_1dof" (Eq. 5.484) or "planar" (Eq. 5.56)
    report: list[dict]
    omega: float  # drive angular speed (rad/s)
    period: float  # drive period T (s)
    omega_max: float  # fastest rate in the scene (rad/s), for the step rule
    invariant: str  # "jacobi", "energy", "energy+momenta" or "none"
    invariant_reason: str
    body_names: list[str] = field(default_factory=list)
    bf: np.ndarray | None = None
    bi: np.ndarray | None = None
    src: np.ndarray | None = None
    fld: np.ndarray | None = None
    flags: np.ndarray | None = None
    g: np.ndarray | None = None
    x0: np.ndarray | None = None
    v0: np.ndarray | None = None
    R0: np.ndarray | None = None  # principal frame -> lab
    L0: np.ndarray | None = None  # lab angular momentum about the CM
    frames: np.ndarray | None = None  # body frame -> principal frame change V (R_body = R_p V^T)
    axis: np.ndarray = field(default_factory=lambda: np.zeros(3))
    r_escape: float = 0.0
    length_scale: float = 1e-3
    reduced: ReducedForm | None = None
    wz: float = 0.0  # signed drive speed in the Jacobi constant K = E - wz J_z

    def kernel_args(self) -> tuple:
        """The step kernels' scene arguments, packed once: ``(bf, bi, src, fld, flags, g, axis,
        r_escape, wz)`` (the layout of :mod:`labkit.sim.integrators.kernels`)."""
        packed = self.__dict__.get("_kernel_args")
        if packed is None:
            packed = (self.bf, self.bi, self.src, self.fld, self.flags, self.g, self.axis,
                      float(self.r_escape), float(self.wz))
            self.__dict__["_kernel_args"] = packed
        return packed

    def summary(self) -> dict:
        """JSON-ready description of the compiled system."""
        out = {
            "kind": self.kind,
            "omega_rad_s": self.omega,
            "period_s": self.period,
            "omega_max_rad_s": self.omega_max,
            "invariant": self.invariant,
            "invariant_reason": self.invariant_reason,
            "report": self.report,
        }
        if self.reduced is not None:
            out["equation"] = self.reduced.equation
        if self.kind == "rigid":
            out["flags"] = {
                k: bool(self.flags[i])
                for i, k in enumerate(["field", "rotators", "body_pairs", "gravity", "damping", "forces"])
            }
            out["escape_radius_m"] = self.r_escape or None
        return out


def _principal(body: SceneBody) -> tuple[np.ndarray, np.ndarray, int, str]:
    """Principal moments (symmetric-top axis third), frame change V (det +1), free kind, label."""
    inertia = np.asarray(body.inertia_kg_m2, dtype=float)
    eig, vec = np.linalg.eigh(inertia)
    close = lambda a, b: math.isclose(a, b, rel_tol=1e-9)  # noqa: E731
    if close(eig[0], eig[2]):
        return np.full(3, eig.mean()), np.eye(3), 0, "isotropic: exact free rotation"
    if np.allclose(inertia, np.diag(np.diag(inertia))) and close(inertia[0, 0], inertia[1, 1]):
        return np.diag(inertia).copy(), np.eye(3), 0, "symmetric top: exact free rotation"
    if close(eig[1], eig[2]):
        order = [1, 2, 0]
        eig, vec = eig[order], vec[:, order]
        kind, label = 0, "symmetric top: exact free rotation"
    elif close(eig[0], eig[1]):
        kind, label = 0, "symmetric top: exact free rotation"
    else:
        kind, label = 1, "three unequal moments: DLM planar-rotation sequence"
    if np.linalg.det(vec) < 0:
        vec[:, 0] = -vec[:, 0]
    return eig, vec, kind, label


def _dipole_lab(body: SceneBody) -> np.ndarray:
    return body.rotation @ np.asarray(body.moment_Am2, dtype=float)


def _try_reduced(scene: Scene) -> tuple[ReducedForm | None, str]:
    """The reduced one-DoF form if the scene is exactly Eq. 5.484 or Eq. 5.56."""
    if len(scene.bodies) != 1 or scene.rotators or scene.field is None:
        return None, "not a single body in a uniform field"
    b, fld = scene.bodies[0], scene.field
    inertia = np.asarray(b.inertia_kg_m2, dtype=float)
    if not np.allclose(inertia, inertia[0, 0] * np.eye(3), rtol=1e-12, atol=0.0):
        return None, "inertia is not isotropic"
    if b.damping_rot_N_m_s > 0:
        return None, "rotational damping present"
    m = float(np.linalg.norm(b.moment_Am2))
    if m == 0.0:
        return None, "body has no dipole"
    psi = _dipole_lab(b) / m
    w = np.asarray(b.angular_velocity_rad_s, dtype=float)
    tol = 1e-12
    i0 = inertia[0, 0]
    if fld.kind == "oscillating" and abs(psi[0]) < tol and np.all(np.abs(w[1:]) <= tol * max(1.0, abs(w[0]))):
        y0 = math.atan2(-psi[1], psi[2])
        return ReducedForm(
            0, m * fld.B_c_T / i0, m * fld.B_s_T / i0, fld.omega_rad_s, fld.phase_rad, y0, float(w[0]), i0, m
        ), ""
    if (
        fld.kind == "rotating"
        and fld.B_s_T == 0.0
        and abs(psi[2]) < tol
        and np.all(np.abs(w[:2]) <= tol * max(1.0, abs(w[2])))
    ):
        y0 = math.atan2(psi[0], -psi[1])
        return ReducedForm(
            1, m * fld.B_c_T / i0, 0.0, fld.omega_rad_s, fld.phase_rad, y0, float(w[2]), i0, m
        ), ""
    return None, "dipole or spin not confined to the field's plane"


Note = Callable[[str, str, str], None]


def compile_scene(scene: Scene, reduce: bool = True) -> CompiledSystem:
    """Compile ``scene`` (see module docstring); the result's ``report`` lists every decision.

    ``reduce=False`` keeps the full rigid-body system even when a reduced form applies
    (to cross-check the reduction or to benchmark it). Each decision is one function below.
    """
    report: list[dict] = []

    def note(item: str, action: str, reason: str) -> None:
        report.append({"item": item, "action": action, "reason": reason})

    reduced, why_not = _try_reduced(scene) if reduce else (None, "switched off (reduce=False)")
    if reduced is not None:
        return _compile_reduced(scene, reduced, report, note)
    note("reduced forms", "not used", why_not)
    has_dipole = [float(np.linalg.norm(b.moment_Am2)) > 0 for b in scene.bodies]
    pairs = sum(has_dipole) >= 2
    forces = len(scene.rotators) > 0 or pairs
    if not forces:
        note("translation", "dropped",
             "no rotator and fewer than two dipole bodies: no magnetic force; the CM moves in closed form")
    bodies = _body_tables(scene, forces, has_dipole, note)
    bf, bi = bodies["bf"], bodies["bi"]
    src = _rotator_table(scene, note)
    fvec = _field_vector(scene, note)
    note("body pairs", "kept" if pairs else "dropped",
         "dipole-dipole force and torque between free bodies (Eq. 4.2-4.3)" if pairs
         else "fewer than two dipole bodies")
    translating = bool(np.any(bi[:, 0]))
    gravity = _decide_gravity(scene, translating, note)
    damping = _decide_damping(bf, bi, note)
    flags = np.zeros(6, dtype=np.int64)
    flags[[F_FIELD, F_SOURCES, F_PAIRS, F_GRAVITY, F_DAMPING, F_FORCES]] = [
        int(fvec[0] != 0), int(len(scene.rotators) > 0), int(pairs), int(gravity), int(damping), int(forces)]
    g = np.asarray(scene.gravity_m_s2, dtype=float) if gravity else np.zeros(3)
    length, seps = _length_scale(scene)
    omega = scene.drive_omega()
    omega_max = _fastest_rate(scene, bf, bi, fvec, has_dipole, omega)
    inv, why, axis = _invariant(scene, fvec, gravity, damping, translating)
    note("invariant", "monitored" if inv != "none" else "none", why)
    r_escape = scene.escape_radius_m or (20.0 * max(seps) if seps and translating else 0.0)
    system = CompiledSystem(
        scene, "rigid", report, omega, scene.period(), omega_max, inv, why, [b.name for b in scene.bodies],
        bf, bi, src, fvec, flags, g, bodies["x0"], bodies["v0"], bodies["R0"], bodies["L0"],
        bodies["frames"], axis, r_escape, length,
    )
    if inv.startswith("jacobi"):
        system.wz = _drive_rate(fvec, src)
    return system


def _compile_reduced(scene: Scene, reduced: ReducedForm, report: list[dict], note: Note) -> CompiledSystem:
    """The one-DoF system of Eq. 5.484 or Eq. 5.56 (one angle, one rate)."""
    omega = scene.drive_omega()
    kind = "reduced_1dof" if reduced.form == 0 else "planar"
    note("rotation", "reduced", "one isotropic body with dipole and spin in the field's plane: "
         f"integrating {reduced.equation} (one angle, one rate)")
    note("translation", "dropped", "uniform field exerts no force; the CM moves in closed form")
    for absent in ("gravity", "damping"):
        note(absent, "dropped", "acts on translation only, which is not integrated")
    inv, why = (
        ("jacobi", "planar Jacobi constant K = p^2/2 + J_C cos(theta - wt) - w p (Eq. 5.56)")
        if reduced.form == 1
        else ("none", "an oscillating drive is not a rigid rotation: no exact invariant")
    )
    w_max = max(omega, math.sqrt(abs(reduced.jc) + abs(reduced.js)), abs(reduced.yd0))
    return CompiledSystem(scene, kind, report, omega, scene.period(), w_max, inv, why,
                          body_names=[scene.bodies[0].name], reduced=reduced)


def _body_tables(scene: Scene, forces: bool, has_dipole: list[bool], note: Note) -> dict[str, np.ndarray]:
    """Per body: the ``bf``/``bi`` kernel rows, principal frames and the initial state."""
    nb = len(scene.bodies)
    bf = np.zeros((nb, BF_WIDTH))
    bi = np.zeros((nb, 4), dtype=np.int64)
    frames = np.zeros((nb, 3, 3))
    x0, v0, L0, R0 = np.zeros((nb, 3)), np.zeros((nb, 3)), np.zeros((nb, 3)), np.zeros((nb, 3, 3))
    for i, b in enumerate(scene.bodies):
        eig, vec, free_kind, label = _principal(b)
        frames[i] = vec
        R0[i] = b.rotation @ vec
        bf[i, 0] = b.mass_kg
        bf[i, 1:4] = eig
        bf[i, 4:7] = vec.T @ np.asarray(b.moment_Am2, dtype=float)
        bf[i, 7:10] = vec.T @ np.asarray(b.dipole_offset_m, dtype=float)
        bf[i, 10], bf[i, 11], bf[i, 12] = b.damping_N_s_m, b.damping_rot_N_m_s, b.shape.contact_radius_m
        translates = forces and not b.pinned
        bi[i] = [int(translates), free_kind, int(has_dipole[i]), int(forces)]
        x0[i], v0[i] = b.position_m, b.velocity_m_s if translates else np.zeros(3)
        inertia_lab = b.rotation @ np.asarray(b.inertia_kg_m2, dtype=float) @ b.rotation.T
        L0[i] = inertia_lab @ np.asarray(b.angular_velocity_rad_s, dtype=float)
        note(f"rotation of {b.name}", "kept", label)
        if forces and b.pinned:
            note(f"translation of {b.name}", "dropped",
                 "pinned; its force is evaluated for the average, not applied")
        elif forces:
            note(f"translation of {b.name}", "kept", "magnetic forces act on it")
    return {"bf": bf, "bi": bi, "frames": frames, "x0": x0, "v0": v0, "R0": R0, "L0": L0}


def _rotator_table(scene: Scene, note: Note) -> np.ndarray:
    """The ``src`` kernel rows of the driven rotators (prescribed, not integrated)."""
    src = np.zeros((len(scene.rotators), SRC_WIDTH))
    for j, r in enumerate(scene.rotators):
        src[j, :5] = [r.moment_Am2, r.tilt_rad, r.omega_rad_s, r.phase_rad, r.ramp_rad_s2]
        src[j, 5:8], src[j, 8:11], src[j, 11] = r.shift_m, r.axis_point_m, r.contact_radius_m
        note(f"rotator {r.name}", "prescribed",
             "driven at omega(t) = omega + ramp t (Eq. 5.25): not integrated")
    return src


def _field_vector(scene: Scene, note: Note) -> np.ndarray:
    """The ``fld`` kernel row: kind, B_c, B_s, omega, phase (zeros when there is no field)."""
    fld, fvec = scene.field, np.zeros(5)
    if fld is not None and (fld.B_c_T != 0.0 or fld.B_s_T != 0.0):
        w = 0.0 if fld.kind == "static" else fld.omega_rad_s
        fvec[:] = [2.0 if fld.kind == "oscillating" else 1.0, fld.B_c_T, fld.B_s_T, w, fld.phase_rad]
        note("uniform field", "kept", f"{fld.kind}: torque only")
    else:
        note("uniform field", "dropped", "absent")
    return fvec


def _decide_gravity(scene: Scene, translating: bool, note: Note) -> bool:
    """Gravity is integrated only when some body translates."""
    present = scene.gravity_m_s2 is not None and bool(np.any(scene.gravity_m_s2 != 0))
    gravity = present and translating
    note("gravity", "kept" if gravity else "dropped",
         "acts on translating bodies" if gravity else ("no translating body" if present else "absent"))
    return gravity


def _decide_damping(bf: np.ndarray, bi: np.ndarray, note: Note) -> bool:
    """Damping is integrated when it acts on a rotation or on a translating body."""
    damping = bool(np.any(bf[:, 11] > 0) or np.any((bf[:, 10] > 0) & (bi[:, 0] > 0)))
    note("damping", "kept" if damping else "dropped",
         "exact linear-damping sub-flow (Strang)" if damping else "absent or acts on no integrated DoF")
    return damping


def _length_scale(scene: Scene) -> tuple[float, list[float]]:
    """The smallest separation of bodies and rotator axes (the error metric's length) and all of them."""
    points = [b.position_m for b in scene.bodies] + [r.axis_point_m for r in scene.rotators]
    seps = [float(np.linalg.norm(np.asarray(p) - np.asarray(q))) for a, p in enumerate(points)
            for q in points[a + 1:]]
    return (min(seps) if seps else 1e-3), seps


def _fastest_rate(scene: Scene, bf: np.ndarray, bi: np.ndarray, fvec: np.ndarray, has_dipole: list[bool],
                  omega: float) -> float:
    """The fastest rate of the scene (drive, spins, torsional and translational oscillation) for the
    step rule and the tolerances."""
    rates = [omega]
    for i, b in enumerate(scene.bodies):
        m = float(np.linalg.norm(b.moment_Am2))
        torque = m * (abs(fvec[1]) + abs(fvec[2]))
        stiff = 0.0
        others = [(r.axis_point_m, abs(r.moment_Am2)) for r in scene.rotators]
        others += [(o.position_m, float(np.linalg.norm(o.moment_Am2)))
                   for k, o in enumerate(scene.bodies) if k != i and has_dipole[k]]
        for position, mo in others:
            d = max(float(np.linalg.norm(b.position_m - position)), 1e-12)
            torque += 2.0 * K_M * mo * m / d**3
            stiff += 24.0 * K_M * mo * m / d**5
        rates.append(float(np.linalg.norm(b.angular_velocity_rad_s)))
        rates.append(math.sqrt(torque / float(bf[i, 1:4].min())))
        if bi[i, 0]:
            rates.append(math.sqrt(stiff / b.mass_kg))
    return max(rates)


def _drive_rate(fvec: np.ndarray, src: np.ndarray) -> float:
    """Signed drive speed w in K = E - w J_z."""
    if fvec[0] == 1.0 and fvec[3] != 0.0:
        return float(fvec[3])
    return float(src[0, 2]) if src.shape[0] else 0.0


def _invariant(
    scene: Scene, fvec: np.ndarray, gravity: bool, damping: bool, translating: bool
) -> tuple[str, str, np.ndarray]:
    """The scene's exact invariant; with damping, its budget (the invariant minus the exact
    change caused by the damping sub-flows, which must stay constant)."""
    inv, why, axis = _base_invariant(scene, fvec, gravity, translating)
    if not damping or inv == "none":
        return inv, why, axis
    if inv == "jacobi":
        return "jacobi-budget", why + "; minus the change made by damping (exact sub-flow)", axis
    return "energy-budget", "energy E minus the change made by damping (exact sub-flow)", axis


def _base_invariant(
    scene: Scene, fvec: np.ndarray, gravity: bool, translating: bool
) -> tuple[str, str, np.ndarray]:
    if gravity and np.any(np.abs(scene.gravity_m_s2[:2]) > 0):
        return "none", "gravity not along the drive axis breaks the rotational symmetry", np.zeros(3)
    rates = set()
    axes = []
    if fvec[0] == 2.0:
        return "none", "an oscillating drive is not a rigid rotation: no exact invariant", np.zeros(3)
    if fvec[0] == 1.0 and fvec[3] != 0.0:
        rates.add(fvec[3])
    for r in scene.rotators:
        if r.ramp_rad_s2 != 0.0:
            return "none", "a ramped drive speed pumps energy: no exact invariant", np.zeros(3)
        rates.add(r.omega_rad_s)
        axes.append(np.asarray(r.axis_point_m, dtype=float))
    if len(rates) > 1:
        return "none", "drives at different speeds: no exact invariant", np.zeros(3)
    axis = axes[0] if axes else np.zeros(3)
    if any(np.linalg.norm(a[:2] - axis[:2]) > 1e-15 for a in axes):
        return "none", "rotators on different axes: no exact invariant", np.zeros(3)
    if not rates:
        if scene.field is None and not gravity and all(not b.pinned for b in scene.bodies) and translating:
            return (
                "energy+momenta",
                "autonomous free bodies: energy E, momentum P and angular momentum J",
                axis,
            )
        return "energy", "autonomous scene: energy E", axis
    if scene.rotators and any(
        b.pinned and np.linalg.norm(b.position_m[:2] - axis[:2]) > 1e-15 for b in scene.bodies
    ):
        return "none", "a pinned body off the drive axis breaks the rotational symmetry", axis
    w = next(iter(rates))
    return "jacobi", f"uniform drive at {w:.6g} rad/s about z: Jacobi constant K = E - omega J_z", axis
