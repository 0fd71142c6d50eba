"""A scene read from TOML (docs/reference/simulator.md): every key carries its unit (``mass_g`` or
``mass_kg``, ``speed_rpm`` or ``omega_rad_s``) and is converted to SI; an unknown key, one quantity
given in two units or a value out of range is a :class:`labkit.sim.scene.SceneError`
(``file:key: reason``), and the scene built is checked whole (:mod:`labkit.sim.scene_checks`).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from labkit.sim import equilibrium
from labkit.sim.rotations import euler_zxz
from labkit.sim.scene import Rotator, Scene, SceneBody, SceneError, Shape, UniformField
from labkit.sim.scene_checks import validate_bodies, validate_scene
from labkit.units import G0, RAD_S_PER_RPM

MASS_UNITS = {"kg": 1.0, "g": 1e-3}
INERTIA_UNITS = {"kg_m2": 1.0, "g_cm2": 1e-7}
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
ANGLE_UNITS = {"rad": 1.0, "deg": math.pi / 180.0}
FIELD_UNITS = {"T": 1.0, "mT": 1e-3}


class _Table:
    """A TOML table being read: tracks used keys, reports unknown ones, converts units."""

    def __init__(self, data: Any, path: str, source: str) -> None:
        if not isinstance(data, dict):
            raise SceneError(source, path, "expected a table")
        self.data, self.path, self.source, self.used = data, path, source, set()

    def key(self, k: str) -> str:
        return f"{self.path}.{k}" if self.path else k

    def error(self, k: str, reason: str) -> SceneError:
        return SceneError(self.source, self.key(k), reason)

    def get(self, k: str, default: Any = None) -> Any:
        if k in self.data:
            self.used.add(k)
            return self.data[k]
        return default

    def number(self, k: str, default: float | None = None) -> float | None:
        if k in self.data and self.data[k] is None:
            raise self.error(k, "expected a number, got None")
        v = self.get(k, default)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise self.error(k, f"expected a number, got {v!r}")
        if not math.isfinite(v):
            raise self.error(k, "must be finite")
        return float(v)

    def quantity(
        self,
        base: str,
        units: dict[str, float],
        default: Any = None,
        required: bool = False,
        shape: tuple[int, ...] | None = (),
    ) -> Any:
        """Read ``base_<unit>`` for exactly one of ``units``; converted to SI.

        ``shape`` is the required shape (``()`` a number, ``(3,)`` a vector); None accepts any.
        """
        present = [u for u in units if f"{base}_{u}" in self.data]
        if len(present) > 1:
            names = " and ".join(f"{base}_{u}" for u in present)
            raise self.error(f"{base}_{present[1]}", f"inconsistent units: {names} both given")
        if not present:
            if required:
                opts = " or ".join(f"{base}_{u}" for u in units)
                raise self.error(f"{base}_{next(iter(units))}", f"missing (give {opts})")
            return default
        k = f"{base}_{present[0]}"
        raw = self.get(k)
        try:
            arr = np.asarray(raw, dtype=float) * units[present[0]]
        except (TypeError, ValueError):
            raise self.error(k, f"expected numbers, got {raw!r}") from None
        if arr.dtype == object or not np.all(np.isfinite(arr)):
            raise self.error(k, f"expected finite numbers, got {raw!r}")
        if shape is not None and arr.shape != shape:
            want = (
                "a number" if shape == () else f"{shape[0]} numbers" if len(shape) == 1 else f"shape {shape}"
            )
            raise self.error(k, f"expected {want}, got {raw!r}")
        return float(arr) if arr.shape == () else arr

    def string(self, k: str, default: str | None) -> str | None:
        v = self.get(k, default)
        if v is not None and not isinstance(v, str):
            raise self.error(k, f"expected a string, got {v!r}")
        return v

    def boolean(self, k: str, default: bool) -> bool:
        v = self.get(k, default)
        if not isinstance(v, bool):
            raise self.error(k, f"expected true or false, got {v!r}")
        return v

    def tables(self, k: str) -> list:
        v = self.get(k, [])
        if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
            raise self.error(k, f"expected an array of tables ([[{k}]]), got {v!r}")
        return v

    def sub(self, k: str) -> _Table | None:
        v = self.get(k)
        return None if v is None else _Table(v, self.key(k), self.source)

    def finish(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            known = ", ".join(sorted(self.used)) or "none"
            raise self.error(unknown[0], f"unknown key (keys read here: {known})")


def _vec3(t: _Table, base: str, units: dict[str, float], default: Any) -> np.ndarray:
    v = t.quantity(base, units, default=None, shape=(3,))
    if v is None:
        return np.array(default, dtype=float)
    return np.asarray(v, dtype=float)


def _inertia(t: _Table) -> np.ndarray:
    v = t.quantity("inertia", INERTIA_UNITS, required=True, shape=None)
    k = next(f"inertia_{u}" for u in INERTIA_UNITS if f"inertia_{u}" in t.data)
    arr = np.asarray(v, dtype=float)
    if arr.shape == ():
        return np.eye(3) * float(arr)
    if arr.shape == (3,):
        return np.diag(arr)
    if arr.shape == (3, 3):
        return arr
    raise t.error(k, "expected a number (isotropic), 3 principal moments or a 3x3 tensor")


def _shape(t: _Table | None) -> Shape:
    if t is None:
        return Shape()
    kind = t.string("kind", "sphere")
    if kind not in ("sphere", "cylinder", "point"):
        raise t.error("kind", f"unknown shape {kind!r} (sphere, cylinder, point)")
    radius = t.quantity("radius", LENGTH_UNITS, default=0.0)
    height = t.quantity("height", LENGTH_UNITS, default=0.0)
    t.finish()
    if radius < 0 or height < 0:
        raise t.error("radius_m", "must not be negative")
    return Shape(kind, radius, height)


def _omega(t: _Table, required: bool) -> float | None:
    keys = [k for k in ("omega_rad_s", "speed_rpm", "frequency_hz") if k in t.data]
    if len(keys) > 1:
        raise t.error(keys[1], f"inconsistent units: {' and '.join(keys)} both given")
    if not keys:
        if required:
            raise t.error("omega_rad_s", "missing (give omega_rad_s, speed_rpm or frequency_hz)")
        return None
    k = keys[0]
    value = t.number(k)
    return value * {"omega_rad_s": 1.0, "speed_rpm": RAD_S_PER_RPM, "frequency_hz": 2.0 * math.pi}[k]


def _field(t: _Table, bodies_moment: float) -> UniformField:
    kind = t.string("kind", "rotating")
    if kind not in ("rotating", "oscillating", "static"):
        raise t.error("kind", f"unknown field kind {kind!r} (rotating, oscillating, static)")
    omega = _omega(t, required=kind != "static") or 0.0
    values = {}
    for part in ("c", "s"):
        b = t.quantity(f"B_{part}", FIELD_UNITS)
        tau = t.number(f"tau_{part}_Nm")
        if b is not None and tau is not None:
            raise t.error(f"tau_{part}_Nm", f"inconsistent units: B_{part} and tau_{part}_Nm both given")
        if tau is not None:
            if bodies_moment <= 0:
                raise t.error(f"tau_{part}_Nm", "a torque coefficient needs a body with a dipole moment")
            b = tau / bodies_moment  # tau = |m| |B| (Eq. 5.22)
        values[part] = b or 0.0
    phase = t.quantity("phase", ANGLE_UNITS, default=0.0)
    t.finish()
    if kind != "static" and omega == 0.0:
        raise t.error("omega_rad_s", f"a {kind} field needs a non-zero speed")
    return UniformField(kind, values["c"], values["s"], omega, phase)


def _rotator(t: _Table, i: int) -> Rotator:
    name = t.string("name", f"rotator{i}")
    moment = t.number("moment_Am2")
    if moment is None:
        raise t.error("moment_Am2", "missing")
    omega = _omega(t, required=True)
    tilt = t.quantity("tilt", ANGLE_UNITS, default=0.0)
    phase = t.quantity("phase", ANGLE_UNITS, default=0.0)
    ramp = t.number("ramp_rad_s2", 0.0)
    shift = _vec3(t, "shift", LENGTH_UNITS, [0, 0, 0])
    axis = _vec3(t, "axis_point", LENGTH_UNITS, [0, 0, 0])
    radius = t.quantity("radius", LENGTH_UNITS, default=0.0)
    t.finish()
    return Rotator(name, moment, omega, tilt, phase, ramp, shift, axis, radius)


def _moment(t: _Table) -> np.ndarray:
    if "moment_Am2" in t.data and "moment_vector_Am2" in t.data:
        raise t.error("moment_vector_Am2", "give moment_Am2 (along body z) or moment_vector_Am2, not both")
    if "moment_vector_Am2" in t.data:
        return _vec3(t, "moment_vector", {"Am2": 1.0}, [0, 0, 0])
    m = t.number("moment_Am2", 0.0)
    return np.array([0.0, 0.0, m])


def _body(t: _Table, i: int) -> tuple[SceneBody, _Table | None]:
    name = t.string("name", f"body{i}")
    mass = t.quantity("mass", MASS_UNITS, required=True)
    inertia = _inertia(t)
    moment = _moment(t)
    offset = _vec3(t, "dipole_offset", LENGTH_UNITS, [0, 0, 0])
    shape = _shape(t.sub("shape"))
    pinned = t.boolean("pinned", False)
    damp = t.number("damping_N_s_m", 0.0)
    damp_rot = t.number("damping_rot_N_m_s", 0.0)
    init = t.sub("initial")
    t.finish()
    body = SceneBody(name, mass, inertia, moment, offset, shape, pinned, damp, damp_rot)
    return body, init


def _initial(body: SceneBody, t: _Table, scene: Scene) -> None:
    body.position_m = _vec3(t, "position", LENGTH_UNITS, [0, 0, 0])
    body.velocity_m_s = _vec3(t, "velocity", {"m_s": 1.0}, [0, 0, 0])
    euler = t.quantity("euler_zxz", ANGLE_UNITS, shape=(3,))
    matrix = t.get("rotation_matrix")
    if euler is not None and matrix is not None:
        raise t.error("rotation_matrix", "give euler_zxz_rad or rotation_matrix, not both")
    if euler is not None:
        body.rotation = euler_zxz(*np.asarray(euler, dtype=float))
    elif matrix is not None:
        try:
            r = np.asarray(matrix, dtype=float)
        except (TypeError, ValueError):
            raise t.error("rotation_matrix", f"expected a 3x3 matrix, got {matrix!r}") from None
        if (
            r.shape != (3, 3)
            or not np.all(np.isfinite(r))
            or not np.allclose(r.T @ r, np.eye(3), atol=1e-9)
            or np.linalg.det(r) < 0
        ):
            raise t.error("rotation_matrix", "not a proper rotation (R^T R = I, det R = +1)")
        body.rotation = r
    body.angular_velocity_rad_s = _vec3(t, "angular_velocity", {"rad_s": 1.0}, [0, 0, 0])
    eq = t.string("equilibrium", None)
    spin_k = t.number("spin_k", -1.0)
    t.finish()
    if eq is None:
        return
    if eq != "conical":
        raise t.error("equilibrium", f"unknown helper {eq!r} (conical)")
    try:
        equilibrium.apply_conical(body, scene, spin_k=spin_k)
    except ValueError as exc:
        raise t.error("equilibrium", str(exc)) from None
    except ArithmeticError as exc:  # e.g. omega**2 past the float range: no state to start from
        raise t.error("equilibrium", f"cannot be computed from these values ({exc})") from None


def scene_from_dict(data: dict, source: str = "<dict>") -> Scene:
    """Build and validate a scene from a parsed TOML document (see docs/reference/simulator.md)."""
    top = _Table(data, "", source)
    meta = top.sub("scene") or _Table({}, "scene", source)
    name = meta.string("name", Path(source).stem)
    description = meta.string("description", "")
    cycles = meta.get("cycles", 100)
    if isinstance(cycles, bool) or not isinstance(cycles, int) or cycles <= 0:
        raise meta.error("cycles", "must be a positive whole number")
    period = meta.number("period_s")
    escape = meta.quantity("escape_radius", LENGTH_UNITS)
    meta.finish()

    raw_bodies = top.tables("body")
    if not raw_bodies:
        raise SceneError(source, "body", "a scene needs at least one [[body]]")
    bodies, inits = [], []
    for i, raw in enumerate(raw_bodies):
        b, init = _body(_Table(raw, f"body[{i}]", source), i)
        bodies.append(b)
        inits.append(init)
    rotators = [
        _rotator(_Table(raw, f"rotator[{i}]", source), i) for i, raw in enumerate(top.tables("rotator"))
    ]
    moment = max((float(np.linalg.norm(b.moment_Am2)) for b in bodies), default=0.0)
    ftab = top.sub("field")
    fld = _field(ftab, moment) if ftab is not None else None
    gtab = top.sub("gravity")
    gravity = None
    if gtab is not None:
        gravity = _vec3(gtab, "g", {"m_s2": 1.0}, [0.0, 0.0, -G0])
        gtab.finish()
    top.finish()
    scene = Scene(name, bodies, rotators, fld, gravity, escape, period, cycles, description, source)
    validate_bodies(scene)
    for b, init in zip(bodies, inits, strict=True):
        if init is not None:
            _initial(b, init, scene)
    validate_scene(scene)
    return scene


def load_scene(path: str | Path) -> Scene:
    """Read a scene TOML file (or a bundled scene's name, e.g. ``conical_5_1``)."""
    p = Path(path)
    if not p.exists():
        bundled = Path(__file__).resolve().parent.parent / "data" / "scenes" / f"{p.stem}.toml"
        if p.suffix in ("", ".toml") and bundled.exists():
            p = bundled
        else:
            raise SceneError(str(path), "", "no such scene file (nor a bundled scene of that name)")
    try:
        with open(p, "rb") as fh:
            raw = fh.read(MAX_SCENE_FILE_BYTES + 1)  # bounded: a scene path of /dev/zero
    except OSError as exc:
        raise SceneError(str(p), "", f"cannot read: {exc.strerror or exc}") from None
    if len(raw) > MAX_SCENE_FILE_BYTES:
        raise SceneError(str(p), "", f"larger than {MAX_SCENE_FILE_BYTES // 1000} kB; not a scene file")
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise SceneError(str(p), "", f"not UTF-8 text (byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(str(p), "", f"not valid TOML: {exc}") from None
    except RecursionError:
        raise SceneError(str(p), "", "not valid TOML: nested too deeply") from None
    return scene_from_dict(data, source=str(p))


#: A scene file is a few kB; a bigger one is refused before it is read.
MAX_SCENE_FILE_BYTES = 1_000_000


def bundled_scenes() -> list[str]:
    """Names of the scenes shipped in ``labkit/data/scenes``."""
    d = Path(__file__).resolve().parent.parent / "data" / "scenes"
    return sorted(p.stem for p in d.glob("*.toml"))
