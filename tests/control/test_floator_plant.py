"""The spin-critical plant (Fig. 6.18): Eq. 6.37's critical spin, spin-up, drop and re-placing."""

import math

import pytest

from labkit.emulators.plant import make_plant
from labkit.emulators.rig_plant import FloatorPlant, SpinCriticalLaw


def test_critical_spin_solves_eq_6_37():
    law = SpinCriticalLaw(c=4.7e5, w_ref_rad_s=3000.0)
    for w in (650.0, 800.0, 1100.0):
        v = law.critical_spin(w)
        k = v / w - 1.0
        assert -k * w**2 == pytest.approx(4.7e5 * (1 - w / 3000.0))
    w0 = law.min_trap_speed()
    assert law.critical_spin(w0) == pytest.approx(0.0, abs=1e-6)
    # the paper's series 1 starts at 625 rad/s with no spin
    assert w0 == pytest.approx(625, rel=0.03)


def test_floator_spins_up_and_drops_at_the_critical_spin_then_is_placed_again():
    plant = FloatorPlant(noise_rel=0.0, spin_tau_s=6.0, spin_ratio=0.95, reload_s=2.0)
    w = 800.0
    plant.advance(0.001, lambda t: w)
    assert not plant.present  # nothing held yet: placed reload_s later
    plant.advance(2.05, lambda t: w)
    assert plant.present and plant.spin_rad_s < 10.0  # just placed: spin starts from zero
    v_crit = plant.law.critical_spin(w)
    # first-order spin-up toward 0.95 w: time to reach v_crit
    t_drop = 2.0 - 6.0 * math.log(1 - v_crit / (0.95 * w))
    plant.advance(t_drop - 0.05, lambda t: w)
    assert plant.present
    plant.advance(t_drop + 0.05, lambda t: w)
    assert not plant.present and plant.drops == 1
    assert plant.dropped_at == pytest.approx(t_drop, abs=0.02)


def test_fig618_preset_balance_reads_the_held_floator_weight():
    rig = make_plant("fig618.test")
    rig.set_duty(800 / 2500, 0.0)
    weights = {round(rig.force(t / 10), 4) for t in range(0, 200)}
    assert weights == {0.0, round(13.36e-3 * 9.80665, 4)}
    assert make_plant("fig525").floator is None
