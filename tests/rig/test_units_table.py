"""labkit.units.UNIT_SUFFIXES is the one suffix table: rig files and fit tables read it alike,
and ``_g`` (mass, kg) and ``_gf`` (force, N) never mean the same thing."""

from __future__ import annotations

import numpy as np
import pytest

from labkit.fit.data import to_si
from labkit.rig import parse_body
from labkit.rig.checks import split_unit
from labkit.units import G0, UNIT_SUFFIXES, column_to_si


def test_rig_files_and_fit_tables_share_the_table():
    import labkit.rig.checks

    assert labkit.rig.checks.UNIT_SUFFIXES is UNIT_SUFFIXES
    assert split_unit("max_speed_rpm") == ("max_speed", "rad/s", pytest.approx(2 * np.pi / 60))


def test_grams_are_mass_in_a_rig_file_and_grams_force_in_a_table():
    body = parse_body("t.toml", "floator", {"shape": "sphere", "diameter_mm": 10, "mass_g": 4.0})
    assert body.mass_kg == pytest.approx(4.0e-3, rel=1e-12)
    name, values = to_si("force_gf", np.array([100.0]))
    assert name == "force_n" and values[0] == pytest.approx(100.0 * 1e-3 * G0, rel=1e-12)
    old_name, old_values = to_si("force_g", np.array([100.0]))   # older tables: read as gram-force
    assert old_name == "force_n" and old_values[0] == pytest.approx(values[0], rel=1e-12)


@pytest.mark.parametrize(("column", "si_name", "factor"), [
    ("speed_rpm", "speed_rad_s", 2 * np.pi / 60),
    ("speed_hz", "speed_rad_s", 2 * np.pi),
    ("distance_mm", "distance_m", 1e-3),
    ("cone_angle_deg", "cone_angle_rad", np.pi / 180),
    ("speed_rad_s", "speed_rad_s", 1.0),
    ("series", "series", 1.0),
])
def test_columns_convert_by_suffix(column, si_name, factor):
    name, got = column_to_si(column)
    assert name == si_name and got == pytest.approx(factor, rel=1e-12)
