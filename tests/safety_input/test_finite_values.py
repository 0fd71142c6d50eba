"""Issue 17, deliver 4 (config level): a non-finite or absurd gain, speed, duration or timeout
is refused by the dry run with ``file:key: reason`` and exit 2; nothing moves."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.emulators.plant import shared_plant
from labkit.errors import RigFileError
from labkit.protocols.params import ParamError, parse_number_list
from labkit.rig import load_rig

from .conftest import FIG525, assert_one_line, rig_with, run_cli

RIG_CASES = [
    # (line in the shipped rig, replacement, key named in the error, reason)
    ("kp = 2e-4", "kp = nan", "control.kp", "finite"),
    ("kp = 2e-4", "kp = inf", "control.kp", "finite"),
    ("ki = 4e-4", "ki = inf", "control.ki", "finite"),
    ("ki = 4e-4", "ki = -inf", "control.ki", "finite"),
    ("max_duty = 1.0", "max_duty = nan", "limits.max_duty", "finite"),
    ("max_speed_rpm = 24000", "max_speed_rpm = 1e9", "limits.max_speed_rpm", "sanity cap of 150000 RPM"),
    ("max_speed_rpm = 24000", "max_speed_rpm = nan", "limits.max_speed_rpm", "finite"),
    ("max_ramp_rpm_per_s = 6000", "max_ramp_rpm_per_s = 1e12", "limits.max_ramp_rpm_per_s", "sanity cap"),
    ("full_speed_rpm = 23873", "full_speed_rpm = inf", "control.full_speed_rpm", "finite"),
    ("tach_timeout_s = 0.5", "tach_timeout_s = 1e9", "control.tach_timeout_s", "sanity cap of 10 s"),
    ("tach_timeout_s = 0.5", "tach_timeout_s = nan", "control.tach_timeout_s", "finite"),
    ("settle_timeout_s = 20", "settle_timeout_s = 1e9", "control.settle_timeout_s", "sanity cap of 3600 s"),
    ("period_s = 0.05", "period_s = 60", "control.period_s", "sanity cap of 1 s"),
    ("serial = { baudrate = 9600, timeout = 0.2 }", "serial = { baudrate = 9600, timeout = -1 }",
     "devices.rotor_motor.serial.timeout", "must be in [0, 3600] s"),
    ("serial = { baudrate = 9600, timeout = 0.2 }", "serial = { baudrate = 9600, timeout = nan }",
     "devices.rotor_motor.serial.timeout", "finite"),
    ("serial = { baudrate = 9600, timeout = 0.5 }",
     "serial = { baudrate = 9600, timeout = 0.5 }\noptions = { reply_timeout_s = nan }",
     "devices.balance.options.reply_timeout_s", "finite"),
    ("serial = { baudrate = 115200, timeout = 0.2 }",
     "serial = { baudrate = 115200, timeout = 0.2 }\noptions = { reply_timeout_s = 1e9 }",
     "devices.rotor_tach.options.reply_timeout_s", "must be in [0, 3600]"),
    ("serial = { baudrate = 115200, timeout = 0.2 }",
     "serial = { baudrate = 115200, timeout = 0.2 }\noptions = { zto_ms = -5 }",
     "devices.rotor_tach.options.zto_ms", "must be in [0, 3600000]"),
]


@pytest.mark.parametrize("old, new, key, reason", RIG_CASES, ids=[c[1][:40] for c in RIG_CASES])
def test_rig_value_refused_by_dry_run(old, new, key, reason, tmp_path, capsys):
    rig = rig_with(tmp_path, old, new)
    code, out, err = run_cli(["run", rig, "speed-sweep", "--dry-run"], capsys)
    assert_one_line(code, err, f"{rig}:{key}:", reason)
    assert shared_plant("model-fig525").motor("rotor").duty_changes == []


SET_CASES = [
    ("speeds_rpm=nan", "finite"),
    ("speeds_rpm=6000,inf", "finite"),
    ("speeds_rpm=6000:nan:1000", "finite"),
    ("speeds_rpm=1e9", "sanity cap of 150000 RPM"),
    ("record_s=nan", "finite"),
    ("record_s=inf", "finite"),
    ("record_s=1e9", "must be in [0, 3600] s"),
    ("settle_timeout_s=-1", "must be in [0, 3600] s"),
    ("speeds_rpm=0:20000:1e-9", "more than the limit of 10000"),
    ("repeats=1000000000", "beyond the limit of 10000"),
    ("repeats=5000", "more than the limit of 10000"),
]


@pytest.mark.parametrize("setting, reason", SET_CASES)
def test_set_value_refused_by_dry_run(setting, reason, capsys):
    code, out, err = run_cli(["run", FIG525, "speed-sweep", "--set", setting, "--dry-run"], capsys)
    key = setting.split("=")[0]
    assert_one_line(code, err, f"--set {key}", reason)


def test_spin_critical_tiny_step_is_refused_not_an_endless_plan(capsys):
    code, out, err = run_cli(["run", "emulated-fig618", "spin-critical", "--set", "step_pct=1e-300",
                              "--dry-run"], capsys)
    assert_one_line(code, err, "--set step_pct", "steps, more than the limit")


def test_shipped_rigs_still_load():
    for name in ("emulated-fig525", "emulated-fig618"):
        rig = load_rig(name)
        assert all(math.isfinite(v) for v in (rig.control.kp, rig.control.ki, rig.limits.max_speed_rad_s))


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="0123456789.:,;-+eEnaif ", max_size=40))
def test_parsed_lists_are_finite_capped_or_refused(text):
    try:
        values = parse_number_list("speeds_rpm", text)
    except ParamError as exc:
        assert str(exc).startswith("--set speeds_rpm")
        return
    assert len(values) <= 10_000
    assert all(math.isfinite(v) and abs(v) <= 150_000 for v in values)


@settings(max_examples=200, deadline=None)
@given(st.floats(allow_nan=True, allow_infinity=True))
def test_any_gain_is_finite_or_refused(value):
    text = FIG525.read_text().replace("kp = 2e-4", f"kp = {value!r}".replace("'", ""))
    from labkit.rig import parse_rig

    try:
        rig = parse_rig(text, "r.toml")
    except RigFileError as exc:
        assert exc.key in ("control.kp", "(syntax)"), exc
        return
    assert math.isfinite(rig.control.kp) and rig.control.kp >= 0
