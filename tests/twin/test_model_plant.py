"""The model plant: the balance force and the spin-critical C come from the rig file's magnets."""

import math
from pathlib import Path

import pytest

from labkit.emulators.break_up import break_up
from labkit.emulators.model_plant import Imperfections, model_plant
from labkit.emulators.plant import Emulation, make_plant
from labkit.emulators.twin_model import (
    TwinParams,
    balance_force_table,
    default_params,
    params_from_rig,
    steady_force_n,
    table_error,
)
from labkit.model.pfr_force import dipole_constant, pfr_force
from labkit.rig import load_rig

RIGS = Path(__file__).resolve().parents[2] / "rigs"


def test_table_matches_fresh_steady_state_solves_between_its_nodes():
    assert table_error(TwinParams()) < 2e-4


def test_balance_force_is_the_pfr_of_the_rig_magnets_close_to_the_closed_form_at_high_speed():
    p = TwinParams()
    w = 2000.0  # rad/s: small cone angle, where Eq. 5.77 holds best
    m = dipole_constant(p.m_rotator, p.m_floator)
    _, closed = pfr_force(p.gap_m, m, p.i_radial, w, 2 * math.tan(p.tilt_rad) * m / p.gap_m**3)
    exact = steady_force_n(p, w)
    # the steady state adds the CM-circle part that Eq. 5.77 leaves out (Sec. 5.2): same sign, order
    assert 1.0 < exact / float(closed) < 1.6
    # ~ w^-2 (Eq. 5.81)
    slope = math.log(steady_force_n(p, 2 * w) / exact) / math.log(2.0)
    assert slope == pytest.approx(-2.0, abs=0.02)


def test_force_scales_with_the_moment_product_squared_for_small_cones():
    p = TwinParams()
    q = p.with_product(1.2 * p.moment_product)
    ratio = balance_force_table(q).force_n(2000.0) / balance_force_table(p).force_n(2000.0)
    assert ratio == pytest.approx(1.44, rel=0.02)


def test_shipped_rig_file_feeds_the_model_plant(tmp_path):
    rig = load_rig(RIGS / "emulated-fig525.toml")
    assert params_from_rig(rig) == TwinParams()        # the defaults are the shipped rig's magnets
    emu = Emulation("t", rig=rig)
    plant = emu.plant("model-fig525")
    assert plant.model_force_n(1500.0) == pytest.approx(steady_force_n(TwinParams(), 1500.0), rel=2e-4)
    text = (RIGS / "emulated-fig525.toml").read_text().replace("dipole_moment_a_m2 = 2.0",
                                                                 "dipole_moment_a_m2 = 2.4")
    other = tmp_path / "stronger.toml"
    other.write_text(text)
    emu.bind_rig(load_rig(other))
    stronger = emu.plant("model-fig525").model_force_n(1500.0)
    assert stronger / plant.model_force_n(1500.0) > 1.3


def test_fig618_model_c_follows_the_break_up_and_the_fitted_preset_stays():
    shipped = params_from_rig(load_rig(RIGS / "emulated-fig618.toml"))
    assert default_params("model-fig618") == shipped    # a bare sim:// URL: the shipped rig's magnets
    assert default_params("model-fig525") == params_from_rig(load_rig(RIGS / "emulated-fig525.toml"))
    c = make_plant("model-fig618", seed=1).floator.law.c
    assert c == pytest.approx(break_up(shipped).c)
    assert c == pytest.approx(4.7e5, rel=0.01)          # the shipped rig gives the paper's series 1
    assert make_plant("fig618").floator.law.c == 4.7e5  # the paper's fitted law as a preset
    # the fig525 rig's magnets (rotator tilt 5 deg instead of 6.9) break up elsewhere
    fig525_magnets = model_plant("model-fig618", 1, TwinParams()).floator.law.c
    assert fig525_magnets == pytest.approx(break_up(TwinParams()).c)
    assert break_up(TwinParams()).c > 1.5 * c


def test_imperfections_are_seeded_and_off_when_zeroed():
    quiet = Imperfections(vibration_g=0, tach_jitter_rel=0, tach_drop_p=0, motor_drag=0)
    a, b = model_plant("model-fig525", 3), model_plant("model-fig525", 3)
    q = model_plant("model-fig525", 3, imperfections=quiet)
    for plant in (a, b, q):
        plant.set_duty(0.5, 0.0)
    ra = [a.tach_reading(10 + 0.05 * i) for i in range(200)]
    rb = [b.tach_reading(10 + 0.05 * i) for i in range(200)]
    rq = [q.tach_reading(10 + 0.05 * i) for i in range(200)]
    assert ra == rb and max(rq) - min(rq) < 1e-6 and len(set(ra)) > 100
    assert rq[0] == pytest.approx(0.5 * 2500.0)
    assert max(ra) < rq[0]                               # air drag: the loaded motor runs slower
    assert q.force(10.0) == pytest.approx(q.model_force_n(rq[0]))
    assert a.force(10.0) != pytest.approx(a.model_force_n(a.speed(10.0)), rel=1e-6)  # it shakes
