"""Magnets for a prediction: shape and size -> volume, mass, inertia, dipole moment.

A magnet is described the way a catalogue does (``cylinder:6x3mm``: diameter 6 mm, length
3 mm; ``sphere:10mm``; ``cube:5mm``; ``block:10x5x2mm`` with the last size along the dipole)
or by a rig file's ``[bodies.*]`` table. The moment follows from the remanence and the volume,
m = B_r V / mu0 (paper Eq. 6.16); the mass from the volume and the density of sintered NdFeB;
the inertia from the shape (uniform density). Everything returned is SI.

Conventions (the paper's set-ups, Sec. 5.8 and 6.7): a floator's dipole lies along its
symmetry axis (axially magnetised, ``length`` along the dipole); a rotator spins about its own
symmetry axis with its moment nearly across it (diametric magnetisation, tilted by gamma), so
its extent along the spin axis is half its ``length`` (or its radius for a sphere).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from labkit.bodies import GRADE_REMANENCE_T, MU0, NDFEB_DENSITY_KG_M3, shape_properties

DEFAULT_GRADE = "N42"
SHAPES = ("sphere", "cylinder", "cube", "block")


class MagnetSpecError(ValueError):
    """A magnet description that cannot be read (message names the problem)."""


@dataclass(frozen=True)
class Magnet:
    """One magnet, SI: m, kg, kg m^2, A m^2. ``sizes_m`` as given (diameter/length/...)."""

    shape: str
    sizes_m: tuple[float, ...]
    mass_kg: float
    inertia_axial_kg_m2: float
    inertia_radial_kg_m2: float
    moment_a_m2: float
    axial_half_extent_m: float     # half its extent along the dipole / spin axis
    size_m: float                  # largest dimension (for the point-dipole caveat)
    remanence_t: float | None = None
    source: str = ""               # how the numbers were obtained, for the report

    def to_json(self) -> dict:
        return {
            "shape": self.shape, "sizes_mm": [s * 1e3 for s in self.sizes_m],
            "mass_g": self.mass_kg * 1e3, "inertia_axial_kg_m2": self.inertia_axial_kg_m2,
            "inertia_radial_kg_m2": self.inertia_radial_kg_m2, "moment_a_m2": self.moment_a_m2,
            "remanence_t": self.remanence_t, "source": self.source,
        }


def remanence_for_grade(grade: str) -> float:
    """B_r (T) of an NdFeB grade such as ``N42`` (suffixes like ``N42SH`` keep the base grade)."""
    m = re.fullmatch(r"(N\d\d)[A-Z]*", grade.strip().upper())
    if not m or m.group(1) not in GRADE_REMANENCE_T:
        known = ", ".join(GRADE_REMANENCE_T)
        raise MagnetSpecError(f"unknown grade {grade!r}; known: {known}")
    return GRADE_REMANENCE_T[m.group(1)]


def moment_from_remanence(remanence_t: float, volume_m3: float) -> float:
    """Dipole moment m = B_r V / mu0 (A m^2) of a uniformly magnetised body (Eq. 6.16)."""
    return remanence_t * volume_m3 / MU0


_N_SIZES = {"sphere": 1, "cylinder": 2, "cube": 1, "block": 3}


def build_magnet(shape: str, sizes_m: tuple[float, ...], remanence_t: float | None = None,
                 mass_kg: float | None = None, moment_a_m2: float | None = None,
                 inertia_axial_kg_m2: float | None = None, inertia_radial_kg_m2: float | None = None,
                 grade: str = "") -> Magnet:
    """A :class:`Magnet`; given values win, missing ones come from the shape (Eq. 6.16 for m)."""
    if shape not in _N_SIZES:
        raise MagnetSpecError(f"unknown shape {shape!r}; use one of {', '.join(SHAPES)}")
    if len(sizes_m) != _N_SIZES[shape]:
        raise MagnetSpecError(f"a {shape} needs {_N_SIZES[shape]} size(s), got {len(sizes_m)}")
    if any(not math.isfinite(s) or s <= 0 for s in sizes_m):
        raise MagnetSpecError(f"sizes must be positive, got {[s * 1e3 for s in sizes_m]} mm")
    volume, i_ax, i_rad, half = shape_properties(shape, sizes_m)
    notes = []
    if mass_kg is None:
        mass_kg = NDFEB_DENSITY_KG_M3 * volume
        notes.append("mass from volume at 7.5 g/cm^3")
    if moment_a_m2 is None:
        if remanence_t is None:
            remanence_t = remanence_for_grade(grade or DEFAULT_GRADE)
            notes.append(f"B_r {remanence_t:g} T ({grade or DEFAULT_GRADE + ', default'})")
        else:
            notes.append(f"B_r {remanence_t:g} T")
        if not 0 < remanence_t < 2:
            raise MagnetSpecError(f"remanence must be in (0, 2) T, got {remanence_t}")
        moment_a_m2 = moment_from_remanence(remanence_t, volume)
        notes.append("moment from Eq. 6.16")
    if inertia_axial_kg_m2 is None or inertia_radial_kg_m2 is None:
        notes.append("inertia from shape")
    return Magnet(
        shape=shape, sizes_m=tuple(sizes_m), mass_kg=mass_kg,
        inertia_axial_kg_m2=inertia_axial_kg_m2 if inertia_axial_kg_m2 is not None else mass_kg * i_ax,
        inertia_radial_kg_m2=inertia_radial_kg_m2 if inertia_radial_kg_m2 is not None else mass_kg * i_rad,
        moment_a_m2=moment_a_m2, axial_half_extent_m=half, size_m=max(sizes_m),
        remanence_t=remanence_t, source="; ".join(notes) or "all given",
    )


_SPEC = re.compile(r"^(?P<shape>[a-z]+):(?P<sizes>[0-9.eE+-]+(?:x[0-9.eE+-]+)*)(?P<unit>mm|cm|m)$")
_UNIT = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}


def parse_magnet_spec(text: str, remanence_t: float | None = None, grade: str = "") -> Magnet:
    """``cylinder:6x3mm`` / ``sphere:10mm`` / ``cube:5mm`` / ``block:10x5x2mm`` -> :class:`Magnet`."""
    m = _SPEC.match(text.strip().lower())
    if not m:
        raise MagnetSpecError(
            f"cannot read {text!r}: expected SHAPE:SIZESUNIT, "
            "e.g. cylinder:6x3mm, sphere:10mm, block:10x5x2mm"
        )
    try:
        sizes = tuple(float(s) * _UNIT[m.group("unit")] for s in m.group("sizes").split("x"))
    except ValueError:
        raise MagnetSpecError(f"cannot read the sizes in {text!r}") from None
    return build_magnet(m.group("shape"), sizes, remanence_t=remanence_t, grade=grade)
