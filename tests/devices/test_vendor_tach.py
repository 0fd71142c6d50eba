"""Lutron 16-byte stream: annunciator codes that are no speed of rotation are never RPM.

Source: the Lutron 16-digit RS-232 data format as printed in Lutron's meter manuals
(D12 D11 annunciator): besides degC/degF/m/s..., the vibration/tachometer meters use
03 (%), 93 (mm/s), 94 (mm), 95 (cm/s), 96 (inch), 98 (inch/s), and some meters letter
codes such as ``B2`` (issue 14, checked against the manuals' unit tables). Before this
fix a 12.3 mm/s frame became 1.288 rad/s.
"""

from __future__ import annotations

import pytest

from labkit.devices.registry import driver_class
from labkit.devices.tachometer.lutron16 import parse_lutron16
from labkit.emulators.plant import reset_plants
from labkit.errors import DeviceTimeout
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port
from labkit.units import RAD_S_PER_RPM


@pytest.fixture(autouse=True)
def _fresh_plants():
    reset_plants()
    yield
    reset_plants()


def frame(annunciator: bytes, digits: bytes = b"00000123", point: bytes = b"1") -> bytes:
    return b"\x024" + b"1" + annunciator + b"0" + point + digits + b"\r"


def open_lutron(query: str, **options):
    clock = VirtualClock()
    cls = driver_class("tachometer", "lutron16")
    port = open_port(f"sim://lutron16?plant=lu{query}", clock=clock, timeout=0, **cls.default_serial)
    return cls(port, clock, name="lutron", **options), clock


@pytest.mark.parametrize("code, unit", [(b"03", "%"), (b"93", "mm/s"), (b"94", "mm"),
                                        (b"95", "cm/s"), (b"96", "inch"), (b"98", "inch/s")])
def test_non_rotation_unit_codes_are_refused_naming_the_unit(code, unit):
    tach, clock = open_lutron(f"&annunciator={code.decode()}")
    with pytest.raises(ValueError, match=f"is {unit}, not a rotation speed"):
        tach.parse_frame(0.0, frame(code))
    with pytest.raises(DeviceTimeout, match="refuses"):
        tach.wait_reading(timeout=3.0)
    assert tach.frames_rejected >= 2
    tach.close()


def test_letter_code_b2_is_parsed_but_never_rpm():
    assert parse_lutron16(frame(b"B2")).annunciator == "B2"
    tach, clock = open_lutron("&annunciator=B2")
    with pytest.raises(ValueError, match="no rotation unit code"):
        tach.parse_frame(0.0, frame(b"B2"))
    with pytest.raises(DeviceTimeout):
        tach.wait_reading(timeout=3.0)
    tach.close()


def test_a_letter_code_is_rpm_only_when_the_user_names_it():
    tach, clock = open_lutron("&annunciator=B2", rpm_code="B2")
    reading = tach.parse_frame(0.0, frame(b"B2", b"00030000", b"1"))
    assert reading is not None
    assert reading.value / RAD_S_PER_RPM == pytest.approx(3000.0, abs=1e-9)
    tach.close()
