"""Plausibility of a rig file's numbers: checked against each other and against physics.

Each number of a rig file may be valid on its own (finite, positive, below its cap) and still
be a unit slip: ``gap_mm = 0.025`` (metres typed), ``full_speed_rpm = 400`` (revolutions per
second typed), ``mass_g = 0.0059`` (kilograms typed). :func:`check_plausible` runs after the
schema (:mod:`labkit.rig.config`) and raises :class:`labkit.errors.RigFileError` as
``file:key: reason`` naming the likely slip, before anything is opened. The bounds, and why
each is where it is, are in docs/reference/rig-files.md ("Plausibility").
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from labkit.bodies import MU0, NDFEB_DENSITY_KG_M3, NDFEB_REMANENCE_T, grade_remanence, shape_properties
from labkit.errors import RigFileError
from labkit.rig.checks import MAX_SPEED_RPM, split_unit
from labkit.units import RAD_S_PER_RPM

if TYPE_CHECKING:
    from labkit.rig.config import BodySpec, Rig

#: the feed-forward full speed may sit this far below the speed limit (a full speed is
#: measured once, to a few per cent; the emulated Fig. 5.25 rig has 2500 rad/s = 23873 RPM
#: under a 24000 RPM limit)
FULL_SPEED_TOLERANCE = 0.10
#: densities of a magnet or magnet assembly: lighter than water or denser than gold is a slip
DENSITY_BOUNDS_KG_M3 = (1000.0, 20000.0)
#: B_r = m mu0 / V a dipole moment implies: ferrite magnets have 0.2-0.45 T, sintered NdFeB
#: 1.17-1.49 T; 2 T is the cap `labkit predict --remanence-t` allows (no permanent magnet has it)
REMANENCE_BOUNDS_T = (0.05, 2.0)
#: with an NdFeB ``grade`` given: the remanence the moment implies within this fraction of the
#: grade's, the density within this fraction of 7500 kg/m^3 (datasheets: 7400-7600)
NDFEB_GRADE_TOLERANCE = 0.2
#: a given moment of inertia against the uniform body of its shape and mass
INERTIA_RATIO_BOUNDS = (0.1, 10.0)
#: rotator tilt out of the rotation plane (the paper's rotators: 4-6 deg)
MAX_TILT_DEG = 45.0
#: centre-to-centre gap: below 1 mm no two magnets fit, beyond 1 m no force is measurable
GAP_BOUNDS_M = (1e-3, 1.0)


def check_plausible(rig: Rig, data: dict[str, Any]) -> None:
    """Cross-check a parsed rig (``data``: the file's tables, for the key names as written).

    Raises RigFileError at the first implausible number; a check whose numbers the file does
    not give is skipped.
    """
    keys = _Keys(str(rig.path), data)
    for name, body in rig.bodies.items():
        _check_body(keys, name, body)
    _check_gap(keys, rig)
    _check_full_speed(keys, rig)


def check_body_plausible(file: str, name: str, body: BodySpec, table: dict[str, Any]) -> None:
    """The body checks of :func:`check_plausible` for one ``[bodies.NAME]`` read on its own
    (``labkit predict RIG`` reads only the bodies); ``table`` is that body's TOML table."""
    _check_body(_Keys(file, {"bodies": {name: table}}), name, body)


class _Keys:
    """The key a rig file used for a quantity (``gap_mm`` or ``gap_m``) and its written value."""

    def __init__(self, file: str, data: dict[str, Any]) -> None:
        self.file, self.data = file, data

    def find(self, section: str, base: str) -> tuple[str, float, str] | None:
        """(key, value as written, suffix) of ``section.base_<suffix>``, or None."""
        table: Any = self.data
        for part in section.split("."):
            table = table.get(part, {}) if isinstance(table, dict) else {}
        for key, value in (table.items() if isinstance(table, dict) else ()):
            split = split_unit(key)
            if split and split[0] == base:
                return key, value, key[len(base) + 1:]
        return None

    def error(self, section: str, base: str, reason: str) -> RigFileError:
        found = self.find(section, base)
        return RigFileError(self.file, f"{section}.{found[0] if found else base}", reason)


def body_size_fields(body: BodySpec) -> tuple[float | None, ...] | None:
    """A rig body's sizes in the order :func:`labkit.bodies.shape_properties` takes them (sphere
    diameter; cylinder diameter and length; cube length; block width, diameter as depth, length
    along the dipole), None where the file leaves one out; None for a shape without them (a
    ring, whose hole the file cannot state)."""
    return {
        "sphere": (body.diameter_m,),
        "cylinder": (body.diameter_m, body.length_m),
        "cube": (body.length_m or body.width_m or body.diameter_m,),
        "block": (body.width_m, body.diameter_m, body.length_m),
    }.get(body.shape)


def body_sizes(body: BodySpec) -> tuple[float, ...] | None:
    """:func:`body_size_fields` when the file gives them all, else None."""
    sizes = body_size_fields(body)
    if sizes is None or any(s is None for s in sizes):
        return None
    return tuple(float(s) for s in sizes)  # type: ignore[arg-type]


def _describe(body: BodySpec, sizes: tuple[float, ...]) -> str:
    return f"{' x '.join(f'{s * 1e3:g}' for s in sizes)} mm {body.shape}"


def _check_body(keys: _Keys, name: str, body: BodySpec) -> None:
    section = f"bodies.{name}"
    tilt_deg = math.degrees(abs(body.tilt_rad))
    if tilt_deg > MAX_TILT_DEG:
        raise keys.error(section, "tilt", (
            f"{tilt_deg:g} deg out of the rotation plane: the tilt is measured from the plane the "
            f"dipole turns in, not from the spin axis (docs/reference/model.md, Eq. 5.25; the paper's "
            f"rotators: 4-6 deg); did you mean {90 - tilt_deg:g} deg? Above {MAX_TILT_DEG:g} deg is refused"))
    sizes = body_sizes(body)
    if sizes is None:
        return
    volume, i_axial, i_radial, _ = shape_properties(body.shape, sizes)
    what = _describe(body, sizes)
    if body.mass_kg is not None:
        _check_density(keys, section, body.mass_kg, volume, what)
    if body.dipole_moment_a_m2 is not None:
        _check_moment(keys, section, body.dipole_moment_a_m2, volume, what)
    if body.grade and (b_r := grade_remanence(body.grade)) is not None:
        _check_grade(keys, section, body, b_r, volume, what)
    mass = body.mass_kg if body.mass_kg is not None else NDFEB_DENSITY_KG_M3 * volume
    for base, given, per_mass in (("inertia_axial", body.inertia_axial_kg_m2, i_axial),
                                  ("inertia_radial", body.inertia_radial_kg_m2, i_radial)):
        if given is None:
            continue
        uniform = mass * per_mass
        low, high = INERTIA_RATIO_BOUNDS
        if not low <= given / uniform <= high:
            raise keys.error(section, base, (
                f"{given:.3g} kg m^2 is {given / uniform:.3g} times that of a uniform {what} of "
                f"{mass * 1e3:.3g} g ({uniform:.3g} kg m^2); outside {low:g}-{high:g} times it is a "
                "unit slip (kg_m2 against g_mm2 is a factor 1e9)"))


def _check_density(keys: _Keys, section: str, mass: float, volume: float, what: str) -> None:
    density = mass / volume
    low, high = DENSITY_BOUNDS_KG_M3
    if low <= density <= high:
        return
    written = keys.find(section, "mass")
    hint = ""
    if written and written[2] == "g" and low <= density * 1e3 <= high:
        hint = f"; looks like kilograms: did you mean mass_g = {written[1] * 1e3:g}?"
    elif written and written[2] == "kg" and low <= density * 1e-3 <= high:
        hint = f"; looks like grams: did you mean mass_kg = {written[1] * 1e-3:g}?"
    raise keys.error(section, "mass", (
        f"{mass * 1e3:.4g} g for a {what} is a density of {density:.4g} kg/m^3; a magnet is "
        f"{low:g}-{high:g} kg/m^3 (sintered NdFeB {NDFEB_DENSITY_KG_M3:g}: "
        f"{NDFEB_DENSITY_KG_M3 * volume * 1e3:.3g} g here){hint}"))


def _check_moment(keys: _Keys, section: str, moment: float, volume: float, what: str) -> None:
    remanence = moment * MU0 / volume
    low, high = REMANENCE_BOUNDS_T
    if low <= remanence <= high:
        return
    nd_low, nd_high = (b * volume / MU0 for b in NDFEB_REMANENCE_T)
    raise keys.error(section, "dipole_moment", (
        f"{moment:.4g} A m^2 for a {what} means B_r = m mu0 / V = {remanence:.4g} T (Eq. 6.16); "
        f"a permanent magnet has {low:g}-{high:g} T (sintered NdFeB {NDFEB_REMANENCE_T[0]:g}-"
        f"{NDFEB_REMANENCE_T[1]:g} T: {nd_low:.3g}-{nd_high:.3g} A m^2 here)"))


def _check_grade(keys: _Keys, section: str, body: BodySpec, b_r: float, volume: float, what: str) -> None:
    """A body of NdFeB grade ``body.grade`` (B_r ``b_r``): its moment near B_r V / mu0 and its mass
    near rho V, within :data:`NDFEB_GRADE_TOLERANCE`."""
    tol = NDFEB_GRADE_TOLERANCE
    if body.dipole_moment_a_m2 is not None:
        expected = b_r * volume / MU0
        if abs(body.dipole_moment_a_m2 / expected - 1) > tol:
            raise keys.error(section, "dipole_moment", (
                f"{body.dipole_moment_a_m2:.4g} A m^2 is {body.dipole_moment_a_m2 / expected:.3g} times "
                f"B_r V / mu0 = {expected:.4g} A m^2 of a {what} of grade {body.grade} (B_r {b_r:g} T, "
                f"Eq. 6.16); more than {tol:.0%} off is another grade or a slip"))
    if body.mass_kg is not None:
        expected = NDFEB_DENSITY_KG_M3 * volume
        if abs(body.mass_kg / expected - 1) > tol:
            raise keys.error(section, "mass", (
                f"{body.mass_kg * 1e3:.4g} g is {body.mass_kg / expected:.3g} times the "
                f"{expected * 1e3:.4g} g "
                f"of a {what} of sintered NdFeB ({NDFEB_DENSITY_KG_M3:g} kg/m^3; grade {body.grade}); "
                f"more than {tol:.0%} off is not a solid NdFeB magnet of these sizes"))


def _check_gap(keys: _Keys, rig: Rig) -> None:
    gap = rig.geometry.gap_m
    if gap is None:
        return
    written = keys.find("geometry", "gap")
    key, value, suffix = written if written else ("gap", gap, "m")
    halves = {name: min(sizes) / 2 for name in ("rotator", "floator")
              if name in rig.bodies and (sizes := body_sizes(rig.bodies[name])) is not None}
    need = sum(halves.values()) if len(halves) == 2 else GAP_BOUNDS_M[0]
    metres = suffix == "mm" and need <= gap * 1e3 <= GAP_BOUNDS_M[1]
    if gap < need:
        what = (f"the magnets (their centres are at least {need * 1e3:g} mm apart: rotator "
                f"{halves['rotator'] * 1e3:g} mm + floator {halves['floator'] * 1e3:g} mm, the smallest "
                "half-size of each)" if len(halves) == 2 else f"{need * 1e3:g} mm, the smallest magnet")
        raise keys.error("geometry", "gap", (
            f"{'looks like metres: ' if metres else ''}{value:g} {suffix} is smaller than {what}"
            f"{f'; did you mean {key} = {value * 1e3:g}?' if metres else ''} (the gap is rotator "
            "centre to floator centre)"))
    if gap > GAP_BOUNDS_M[1]:
        hint = (f"; looks like millimetres: did you mean gap_mm = {value:g}?"
                if suffix == "m" and gap * 1e-3 >= need else "")
        raise keys.error("geometry", "gap", (
            f"{gap:g} m between the centres: no force of one magnet on the other is measurable "
            f"beyond {GAP_BOUNDS_M[1]:g} m{hint}"))


def _check_full_speed(keys: _Keys, rig: Rig) -> None:
    written = keys.find("control", "full_speed")
    if written is None:  # the default is a guess the file did not make: nothing to cross-check
        return
    full, limit = rig.control.full_speed_rad_s, rig.limits.max_speed_rad_s
    if full >= limit * (1 - FULL_SPEED_TOLERANCE):
        return
    key, value, suffix = written
    full_rpm, limit_rpm = full / RAD_S_PER_RPM, limit / RAD_S_PER_RPM
    hint = ""
    if suffix == "rpm":  # the unit whose reading lands nearest the limit, above it
        fits = [(abs(math.log(full_rpm * factor / limit_rpm)), unit, factor)
                for unit, factor in (("Hz (revolutions per second)", 60.0), ("rad/s", 1 / RAD_S_PER_RPM))
                if limit_rpm * (1 - FULL_SPEED_TOLERANCE) <= full_rpm * factor <= MAX_SPEED_RPM]
        if fits:
            _, unit, factor = min(fits)
            hint = f"; looks like {unit}: {value:g} {unit.split()[0]} is {full_rpm * factor:.0f} RPM"
    limit_key = (keys.find("limits", "max_speed") or ("max_speed",))[0]
    raise keys.error("control", "full_speed", (
        f"{full_rpm:.5g} RPM is below limits.{limit_key} ({limit_rpm:.5g} RPM): the feed-forward "
        f"(duty = target / full speed) asks full duty for any target above {full_rpm:.5g} RPM and "
        f"drives the rotor to its real full speed; the full speed at duty 1 must be at least the "
        f"speed limit (within {FULL_SPEED_TOLERANCE:.0%}){hint}"))
