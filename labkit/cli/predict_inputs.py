"""Where ``labkit predict`` takes its magnets from: a rig file's ``[bodies]`` or command-line
specs (the command's inputs live with the command: labkit.predict is physics and reads no rig file).

Rig-file problems are :class:`labkit.errors.RigFileError` (``file:key: reason``); bad options
are :class:`PredictInputError` naming the option.
"""

from __future__ import annotations

import math
from pathlib import Path

from labkit.errors import LabkitError, RigFileError
from labkit.predict.magnets import (
    Magnet,
    MagnetSpecError,
    build_magnet,
    parse_magnet_spec,
    remanence_for_grade,
)
from labkit.rig import BodySpec, find_rig_file, parse_body, read_rig_text
from labkit.rig.config import load_toml
from labkit.rig.plausible import body_size_fields, check_body_plausible


class PredictInputError(LabkitError):
    """A bad ``labkit predict`` option (the message names it)."""


def magnet_from_body(body: BodySpec, remanence_t: float | None = None) -> Magnet:
    """A :class:`Magnet` from a rig file's body (sizes by shape: sphere diameter; cylinder
    diameter and length; cube length; block width, diameter as depth, length along the dipole).
    Raises ValueError naming what is missing."""
    sizes = body_size_fields(body)
    if sizes is None:
        raise ValueError(f"shape {body.shape!r} is not supported here (sphere, cylinder, cube, block)")
    if any(s is None for s in sizes):
        need = {"sphere": "diameter_mm", "cylinder": "diameter_mm and length_mm", "cube": "length_mm",
                "block": "width_mm, diameter_mm (depth) and length_mm (along the dipole)"}[body.shape]
        raise ValueError(f"a {body.shape} needs {need} for a prediction")
    return build_magnet(body.shape, sizes, remanence_t=remanence_t, mass_kg=body.mass_kg,
                        moment_a_m2=body.dipole_moment_a_m2, inertia_axial_kg_m2=body.inertia_axial_kg_m2,
                        inertia_radial_kg_m2=body.inertia_radial_kg_m2, grade=body.grade)


def magnets_from_rig(path: str | Path, remanence_t: float | None = None) -> tuple[Magnet, Magnet, float]:
    """(rotator, floator, rotator tilt in rad) from the ``[bodies]`` of a rig file (or a bundled
    rig's name). Only the bodies are read, so a rig still being planned needs no devices."""
    p = find_rig_file(path)
    file = str(path)
    data = load_toml(read_rig_text(p), file)  # bounded (a rig path of /dev/zero), UTF-8 checked
    tables = data.get("bodies")
    if not isinstance(tables, dict):
        raise RigFileError(file, "bodies",
                           "missing: a prediction needs [bodies.rotator] and [bodies.floator]")
    magnets: dict[str, Magnet] = {}
    tilt = 0.0
    for name in ("rotator", "floator"):
        if name not in tables:
            raise RigFileError(file, f"bodies.{name}", "missing (required for a prediction)")
        body = parse_body(file, name, tables[name])
        check_body_plausible(file, name, body, tables[name])  # mass_g = 0.0059: a slip, refused
        if body.grade:
            try:
                remanence_for_grade(body.grade)
            except MagnetSpecError as exc:
                raise RigFileError(file, f"bodies.{name}.grade", str(exc)) from None
        try:
            magnets[name] = magnet_from_body(body, remanence_t)
        except (ValueError, MagnetSpecError) as exc:
            raise RigFileError(file, f"bodies.{name}", str(exc)) from None
        if name == "rotator":
            tilt = body.tilt_rad
    return magnets["rotator"], magnets["floator"], tilt


def magnet_option(option: str, spec: str, remanence_t: float | None, grade: str) -> Magnet:
    """Parse ``--rotator``/``--floator``; errors name the option."""
    try:
        return parse_magnet_spec(spec, remanence_t=remanence_t, grade=grade)
    except MagnetSpecError as exc:
        raise PredictInputError(f"{option}: {exc}") from None


def check_remanence(remanence_t: float | None, grade: str | None) -> float | None:
    """The remanence to use (T) from ``--remanence-t`` or ``--grade`` (None: per magnet / N42)."""
    if remanence_t is not None and grade:
        raise PredictInputError("give --grade or --remanence-t, not both")
    if remanence_t is not None:
        if not (math.isfinite(remanence_t) and 0 < remanence_t < 2):
            raise PredictInputError(f"--remanence-t: must be between 0 and 2 T, got {remanence_t}")
        return remanence_t
    if grade:
        try:
            return remanence_for_grade(grade)
        except MagnetSpecError as exc:
            raise PredictInputError(f"--grade: {exc}") from None
    return None
