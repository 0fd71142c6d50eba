"""The Fig. 6.18 break-up from the rig's magnets (Eq. 6.33-6.34): C of Eq. 6.37 follows from them."""

import math
from dataclasses import replace
from pathlib import Path

import pytest

from labkit.emulators.break_up import (
    W_REF_RAD_S,
    NoBreakUp,
    _net_outward_force,
    break_up,
    c_definition,
    search_heights,
    weakest_hold,
)
from labkit.emulators.plant import Emulation
from labkit.emulators.rig_plant import SpinCriticalLaw
from labkit.emulators.twin_model import TwinParams, params_from_rig
from labkit.errors import RigFileError
from labkit.rig import load_rig

RIGS = Path(__file__).resolve().parents[2] / "rigs"


def test_derived_break_up_is_the_tangent_hold_of_eq_6_33_6_34():
    p = TwinParams()                                    # the magnets of emulated-fig525
    b = break_up(p)
    assert b.derived and 0 < b.phi < 0.1                # the paper: phi < 0.1 rad in these tests
    r0, w0 = b.gap_m, b.omega_rad_s
    h = 1e-5 * r0
    f0 = _net_outward_force(p, r0, w0)[0]
    slope = (_net_outward_force(p, r0 + h, w0)[0] - _net_outward_force(p, r0 - h, w0)[0]) / (2 * h)
    weight = p.mass_kg * 9.80665
    assert abs(f0) < 1e-6 * weight                      # Eq. 6.33: F_A = F_R + F_G
    assert abs(slope) * r0 < 1e-4 * weight              # Eq. 6.34: zero stiffness
    assert weakest_hold(p, 0.99 * w0, *search_heights(p, 0.99 * w0))[0] > 0    # slower: dropped
    assert weakest_hold(p, 1.01 * w0, *search_heights(p, 1.01 * w0))[0] < 0    # faster: held
    # Eq. 5.69 without spin: C_def = w0^2 up to the lateral circle; the law traps from w0
    assert b.c * b.factor == pytest.approx(w0**2, rel=5e-3)
    assert b.factor == pytest.approx(1 - w0 / W_REF_RAD_S)
    assert SpinCriticalLaw(c=b.c).min_trap_speed() == pytest.approx(w0, rel=1e-3)
    assert b.phi_from_c(b.c) == pytest.approx(b.phi, rel=1e-9)


def test_shipped_fig618_rig_breaks_up_where_the_papers_series_1_starts():
    b = break_up(params_from_rig(load_rig(RIGS / "emulated-fig618.toml")))
    assert b.derived
    assert b.c == pytest.approx(4.7e5, rel=0.01)
    assert b.omega_rad_s == pytest.approx(SpinCriticalLaw(c=4.7e5).min_trap_speed(), rel=0.005)
    emu = Emulation("break-up", seed=1)
    emu.bind_rig(load_rig(RIGS / "emulated-fig618.toml"))
    assert emu.plant("model-fig618").floator.law.c == pytest.approx(b.c)


def test_c_follows_the_magnets_the_tilt_most():
    base = break_up(TwinParams())
    weaker = break_up(replace(TwinParams(), m_floator=1.6))
    # a weaker floator breaks up closer in, at nearly the same speed: C moves little
    assert weaker.gap_m < 0.97 * base.gap_m
    assert 0.95 * base.c < weaker.c < 0.99 * base.c
    # more tilt, more static attraction: held from a lower speed, C much smaller
    assert break_up(replace(TwinParams(), tilt_rad=math.radians(7.0))).c < 0.6 * base.c


def _rig_with(tmp_path: Path, line: str) -> Path:
    text = (RIGS / "emulated-fig618.toml").read_text().replace('balance_under = "rotator"',
                                                                f'balance_under = "rotator"\n{line}')
    path = tmp_path / "rig.toml"
    path.write_text(text)
    return path


def test_rig_file_break_phi_overrides_the_derivation(tmp_path):
    p = params_from_rig(load_rig(_rig_with(tmp_path, "break_phi_rad = 0.0855")))
    b = break_up(p)
    assert not b.derived and b.phi == 0.0855 and b.gap_m == pytest.approx(0.0264)
    tau = 1e-7 * p.moment_product / p.gap_m**3
    expected = c_definition(tau * math.cos(p.tilt_rad), 2 * tau * math.sin(p.tilt_rad), p.i_radial, 0.0855)
    assert b.c == pytest.approx(expected, rel=1e-9)
    deg = params_from_rig(load_rig(_rig_with(tmp_path, "break_phi_deg = 4.9")))
    assert deg.break_phi == pytest.approx(math.radians(4.9))


def test_bad_break_phi_names_file_and_key(tmp_path):
    with pytest.raises(RigFileError, match="geometry.break_phi_deg.*90 degrees"):
        load_rig(_rig_with(tmp_path, "break_phi_deg = 95"))
    with pytest.raises(RigFileError, match="geometry.break_phi_rad"):
        load_rig(_rig_with(tmp_path, "break_phi_rad = -0.1"))


def test_untilted_rotator_cannot_hold_the_floator_and_says_so():
    with pytest.raises(NoBreakUp, match="not held beneath the rotator.*tilt 0.00 deg.*break_phi_rad"):
        break_up(replace(TwinParams(), tilt_rad=0.0))


def test_run_on_an_untilted_fig618_rig_fails_with_one_line(tmp_path, capsys):
    from labkit.cli import main
    rig = tmp_path / "untilted.toml"
    rig.write_text((RIGS / "emulated-fig618.toml").read_text().replace("tilt_deg = 6.9", "tilt_deg = 0"))
    code = main(["run", str(rig), "spin-critical", "--sessions", str(tmp_path / "s")])
    err = capsys.readouterr().err
    assert code != 0 and "Traceback" not in err
    [line] = [x for x in err.splitlines() if "not held beneath the rotator" in x]
    assert "break_phi_rad" in line and "tilt 0.00 deg" in line
