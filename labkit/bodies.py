"""Uniform bodies: volume, inertia per unit mass and half extent of a magnet's shape, and the
constants of sintered NdFeB. Pure functions, no labkit imports: used by a prediction
(:mod:`labkit.predict.magnets`) and by the rig file's plausibility checks
(:mod:`labkit.rig.plausible`), which must agree on what a ``cylinder`` 10 x 10 mm is.
"""

from __future__ import annotations

import math
import re

MU0 = 4e-7 * math.pi
NDFEB_DENSITY_KG_M3 = 7500.0  # sintered NdFeB, 7.4-7.6 g/cm^3 in datasheets
#: remanence of the NdFeB grades N35..N55 (T), the datasheet range
NDFEB_REMANENCE_T = (1.17, 1.49)
#: remanence B_r (T), middle of the datasheet range of each grade
GRADE_REMANENCE_T: dict[str, float] = {
    "N35": 1.19, "N38": 1.24, "N40": 1.275, "N42": 1.305, "N45": 1.34,
    "N48": 1.385, "N50": 1.415, "N52": 1.445, "N55": 1.48,
}


def grade_remanence(grade: str) -> float | None:
    """B_r (T) of an NdFeB grade such as ``N42`` or ``N42SH`` (the base grade); None otherwise."""
    match = re.fullmatch(r"(N\d\d)[A-Z]*", grade.strip().upper())
    return GRADE_REMANENCE_T.get(match.group(1)) if match else None


def shape_properties(shape: str, sizes_m: tuple[float, ...]) -> tuple[float, float, float, float]:
    """(volume, I_axial/mass, I_radial/mass, axial half extent) of a uniform body.

    sphere (d), cylinder (d, length along the axis), cube (a), block (w, depth, height along
    the dipole). Inertias per unit mass about the centre; the block's radial value is the mean of
    its two transverse moments. ValueError for another shape.
    """
    if shape == "sphere":
        (d,) = sizes_m
        r = d / 2
        return 4 / 3 * math.pi * r**3, 0.4 * r**2, 0.4 * r**2, r
    if shape == "cylinder":
        d, length = sizes_m
        r = d / 2
        return math.pi * r**2 * length, r**2 / 2, (3 * r**2 + length**2) / 12, length / 2
    if shape == "cube":
        (a,) = sizes_m
        return a**3, a**2 / 6, a**2 / 6, a / 2
    if shape == "block":
        w, b, h = sizes_m
        radial = ((b**2 + h**2) + (w**2 + h**2)) / 24
        return w * b * h, (w**2 + b**2) / 12, radial, h / 2
    raise ValueError(f"unknown shape {shape!r}; use one of sphere, cylinder, cube, block")
