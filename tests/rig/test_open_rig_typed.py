"""labkit.rig.OpenRig hands devices back by kind, typed; a wrong role names what the rig has."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.devices.base import Balance, Tachometer
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import OpenRig, load_rig, open_rig

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def opened():
    rig = load_rig(REPO / "rigs" / "emulated-fig525.toml")
    clock = VirtualClock()
    with use_clock(clock):
        rig_open = open_rig(rig, clock)
        try:
            yield rig_open
        finally:
            rig_open.close()


def test_accessors_by_kind_return_the_drivers_of_that_kind(opened: OpenRig):
    assert isinstance(opened.balance("balance"), Balance)
    assert isinstance(opened.tachometer("rotor_tach"), Tachometer)
    assert set(opened.balances()) == {"balance"}
    assert set(opened.tachometers()) == {"rotor_tach"}
    handle = opened.motor("rotor_motor")
    assert handle is opened.devices["rotor_motor"]          # one handle per motor
    assert handle.raw_driver is opened.motors()["rotor_motor"]


def test_a_role_of_another_kind_names_the_devices_of_the_kind_asked_for(opened: OpenRig):
    with pytest.raises(KeyError) as info:
        opened.balance("rotor_tach")
    message = str(info.value)
    assert "no open balance called 'rotor_tach'" in message and "balances: balance" in message


def test_the_config_module_imports_no_device_code():
    import subprocess
    import sys

    code = ("import sys, labkit.rig.config; "
            "print(sorted(m for m in sys.modules if m.startswith(('labkit.devices', 'labkit.emulators', "
            "'labkit.io.ports', 'labkit.control'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.strip() == "[]"
