"""Third-party MT-SICS clients from PyPI against labkit's MT-SICS emulator on a real
pseudo-terminal (the optional ``interop`` extra; skipped when it is not installed).

* ``mettler_toledo_device`` 1.5.0 (Janelia; with ``serial_interface`` 2.3.1): its ``zero()``
  sends ``ZI`` and returns the reply's status, ``S`` or ``D`` (labkit's emulator used to
  answer ``ZI A``); ``get_mtsics_level``/``get_software_version``/``get_software_id`` send
  ``I1``/``I3``/``I5`` (answered ``ES`` before, a syntax error for the client).
* ``instrumentkit`` 1.0.0b2 ``instruments.mettler_toledo.MTSICS``: serial number, MT-SICS
  level, stable weight as a quantity.
"""

from __future__ import annotations

import pytest

from labkit.emulators.balances import MtSicsEmulator
from labkit.emulators.rig_plant import RigPlant
from labkit.io.clock import RealClock
from labkit.io.pty_host import PtyHost

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def balance_on_pty():
    plant = RigPlant()
    emulator = MtSicsEmulator(plant=plant, seed=4)
    clock = RealClock()
    with PtyHost(emulator, clock=clock) as host:
        clock.sleep(0.3)   # past the power-on banner
        yield host, emulator, plant, clock


def test_mettler_toledo_device_client(balance_on_pty):
    mtd = pytest.importorskip("mettler_toledo_device")
    host, emulator, plant, clock = balance_on_pty
    dev = mtd.MettlerToledoDevice(port=host.path)
    try:
        assert dev.get_serial_number() == emulator.serial_number
        level = dev.get_mtsics_level()
        assert level[0] == "01" and len(level) == 5
        assert dev.get_software_version() and dev.get_software_id()
        model, *_rest, unit = dev.get_balance_data()
        assert model == emulator.model.split()[0] and unit == "g"
        weight, unit, status = dev.get_weight()
        assert unit == "g" and status == "S" and abs(weight) < 0.05
        assert dev.zero() == "S"                      # ZI on a stable load
        plant.set_duty(0.5, clock.now())
        clock.sleep(0.15)                             # the PFR force is still rising
        assert dev.zero() == "D"                      # ZI zeroes a moving load and says so
    finally:
        dev.close()


def test_instrumentkit_mtsics_client(balance_on_pty):
    instruments = pytest.importorskip("instruments")
    host, emulator, plant, clock = balance_on_pty
    inst = instruments.mettler_toledo.MTSICS.open_serial(host.path, 9600, timeout=2)
    assert inst.serial_number == emulator.serial_number
    assert inst.mt_sics[0] == "01"
    weight = inst.weight
    assert str(weight.units) in ("gram", "g") and abs(weight.magnitude) < 0.05
    inst.zero(immediately=True)
