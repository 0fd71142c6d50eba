"""Magnet specs: Eq. 6.16 moments, textbook inertias, clear errors."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.predict.magnets import MU0, MagnetSpecError, parse_magnet_spec, remanence_for_grade


def test_sphere_moment_is_remanence_times_volume_over_mu0():
    # B_r = mu0 * 1e6 T makes m = V * 1e6 A/m (Eq. 6.16): a 10 mm sphere is 5.236e-7 m^3
    m = parse_magnet_spec("sphere:10mm", remanence_t=MU0 * 1e6)
    assert m.moment_a_m2 == pytest.approx(4 / 3 * math.pi * 0.005**3 * 1e6, rel=1e-12)
    assert m.mass_kg == pytest.approx(7500 * 4 / 3 * math.pi * 0.005**3)
    assert m.inertia_axial_kg_m2 == pytest.approx(0.4 * m.mass_kg * 0.005**2)


def test_cylinder_inertia_and_extent():
    m = parse_magnet_spec("cylinder:6x3mm", remanence_t=1.3)
    r, length = 0.003, 0.003
    assert m.inertia_axial_kg_m2 == pytest.approx(m.mass_kg * r**2 / 2)
    assert m.inertia_radial_kg_m2 == pytest.approx(m.mass_kg * (3 * r**2 + length**2) / 12)
    assert m.axial_half_extent_m == pytest.approx(0.0015)
    assert m.moment_a_m2 == pytest.approx(1.3 * math.pi * r**2 * length / MU0)


def test_units_and_other_shapes():
    assert parse_magnet_spec("sphere:1cm").sizes_m == pytest.approx((0.01,))
    cube = parse_magnet_spec("cube:5mm")
    assert cube.inertia_axial_kg_m2 == pytest.approx(cube.mass_kg * 0.005**2 / 6)
    block = parse_magnet_spec("block:10x5x2mm")
    assert block.axial_half_extent_m == pytest.approx(0.001)
    assert block.mass_kg == pytest.approx(7500 * 1e-7)


def test_grades():
    assert remanence_for_grade("n52") > remanence_for_grade("N42") > remanence_for_grade("N35")
    assert remanence_for_grade("N42SH") == remanence_for_grade("N42")
    with pytest.raises(MagnetSpecError, match="unknown grade 'N99'"):
        remanence_for_grade("N99")


@pytest.mark.parametrize("spec, message", [
    ("cylinder6x3mm", "expected SHAPE:SIZESUNIT"),
    ("cone:6x3mm", "unknown shape 'cone'"),
    ("cylinder:6mm", "a cylinder needs 2 size"),
    ("sphere:0mm", "sizes must be positive"),
    ("sphere:10", "expected SHAPE:SIZESUNIT"),
])
def test_bad_specs(spec, message):
    with pytest.raises(MagnetSpecError, match=message):
        parse_magnet_spec(spec)


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="spherecylindcubkx:0123456789.eE+-mc ", max_size=24))
def test_spec_parser_never_crashes(text):
    try:
        m = parse_magnet_spec(text)
    except MagnetSpecError:
        return
    assert m.mass_kg > 0 and m.moment_a_m2 > 0 and m.inertia_axial_kg_m2 > 0 and m.inertia_radial_kg_m2 > 0
    assert all(math.isfinite(s) and s > 0 for s in m.sizes_m)
