"""pyvesc 1.0.5 (PyPI, Liam Bindle) against labkit's VESC packets, driver and emulator.

pyvesc 1.0.5 was written against the firmware of its day: its ``GetValues`` table is the old
layout (six MOSFET temperatures + PCB temperature, firmware up to 3.06), so it is an
independent reading of exactly the layout labkit's firmware-version-aware decoder added.

pyvesc 1.0.5 does not import as installed: ``from PyCRC.CRCCCITT import CRCCCITT``, while its
dependency name ``PyCRC`` now installs ``pycrc`` 0.12 (another project, no such module). The
fixture below supplies that one class from the standard library - ``binascii.crc_hqx(data,
0)``, CRC-CCITT with initial value 0 (XModem), what PyCRC's default ``CRCCCITT()`` computed -
so the CRC on both sides is still code labkit did not write.
"""

from __future__ import annotations

import sys
import textwrap

import pytest
import serial

from labkit.devices.motor.vesc import (
    COMM_GET_VALUES,
    format_request,
    format_set_current,
    format_set_current_brake,
    format_set_duty,
    format_set_rpm,
    parse_packet,
    parse_values,
)
from labkit.emulators.rig_plant import RigPlant
from labkit.emulators.vesc_emulator import VescEmulator
from labkit.io.clock import RealClock
from labkit.io.pty_host import PtyHost

pytestmark = pytest.mark.timeout(60)


@pytest.fixture(scope="module")
def pyvesc(tmp_path_factory):
    shim = tmp_path_factory.mktemp("pycrc_shim")
    (shim / "PyCRC").mkdir()
    (shim / "PyCRC" / "__init__.py").write_text("")
    (shim / "PyCRC" / "CRCCCITT.py").write_text(textwrap.dedent('''
        import binascii

        class CRCCCITT:
            """PyCRC's CRCCCITT (XModem: initial value 0) from the standard library."""

            def __init__(self, version="XModem"):
                self.version = version

            def calculate(self, data):
                return binascii.crc_hqx(bytes(data), 0)
    '''))
    sys.path.insert(0, str(shim))
    try:
        yield pytest.importorskip("pyvesc")
    finally:
        sys.path.remove(str(shim))


def test_set_commands_are_byte_identical_to_pyvesc(pyvesc):
    from pyvesc.messages.getters import GetValues
    from pyvesc.messages.setters import SetCurrent, SetCurrentBrake, SetDutyCycle, SetRPM

    assert format_set_duty(0.5) == pyvesc.encode(SetDutyCycle(50_000))
    assert format_set_duty(-0.25) == pyvesc.encode(SetDutyCycle(-25_000))
    assert format_set_rpm(20_000) == pyvesc.encode(SetRPM(20_000))
    assert format_set_rpm(-123_456) == pyvesc.encode(SetRPM(-123_456))
    assert format_set_current(2.0) == pyvesc.encode(SetCurrent(2000))
    assert format_set_current_brake(1.5) == pyvesc.encode(SetCurrentBrake(1500))
    assert format_request(COMM_GET_VALUES) == pyvesc.encode_request(GetValues)


def test_pyvesc_decodes_labkit_packets(pyvesc):
    msg, consumed = pyvesc.decode(format_set_rpm(-31_337))
    assert type(msg).__name__ == "SetRPM" and msg.rpm == -31_337 and consumed == 10


def test_firmware_3_00_values_agree_between_pyvesc_and_labkit(pyvesc):
    """labkit's emulator at firmware 3.00 answers GET_VALUES on a pty; pyvesc's old-layout
    table and labkit's legacy decoder read the same numbers from the same bytes."""
    from pyvesc.messages.getters import GetValues

    plant = RigPlant()
    emulator = VescEmulator(plant=plant, options={"firmware": "3.00", "vin_v": "24.3"})
    clock = RealClock()
    with PtyHost(emulator, clock=clock) as host:
        clock.sleep(0.05)
        plant.set_duty(0.25, clock.now(), name="rotor")
        clock.sleep(0.3)
        with serial.Serial(host.path, 115200, timeout=0.05) as port:
            port.write(pyvesc.encode_request(GetValues))
            data = b""
            deadline = clock.now() + 2.0
            msg = None
            while msg is None and clock.now() < deadline:
                data += port.read(256)
                msg, _ = pyvesc.decode(data)
    assert msg is not None, data
    payload, _ = parse_packet(data)
    assert payload is not None
    ours = parse_values(payload, firmware=(3, 0))
    assert msg.v_in == pytest.approx(24.3) and ours.input_voltage_v == pytest.approx(24.3)
    assert msg.duty_now == pytest.approx(0.25) and ours.duty == pytest.approx(0.25)
    assert msg.rpm == ours.erpm and msg.rpm > 0
    assert max(msg.temp_mos1, msg.temp_mos2, msg.temp_mos3, msg.temp_mos4, msg.temp_mos5,
               msg.temp_mos6) == pytest.approx(ours.temp_mosfet_c)
    assert msg.temp_pcb == pytest.approx(ours.temp_pcb_c)
    assert msg.current_motor == pytest.approx(ours.current_motor_a)
    assert (msg.tachometer, msg.tachometer_abs) == (ours.tachometer, ours.tachometer_abs)
    assert msg.mc_fault_code == bytes([ours.fault_code])
