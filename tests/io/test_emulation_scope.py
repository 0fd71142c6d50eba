"""Plants belong to an emulation, not to the process: two emulations' ``plant=fig525`` ports
do not share a motor; the test's own emulation (tests/conftest.py) is the current one."""

from __future__ import annotations

from labkit.devices.registry import driver_class
from labkit.emulators import Emulation, current_emulation, use_emulation
from labkit.io import VirtualClock, open_port


def open_balance(clock):
    port = open_port("sim://mtsics?seed=3&plant=fig525&role=balance", clock=clock, timeout=0.5)
    return driver_class("balance", "mtsics")(port, clock, name="balance")


def test_the_test_runs_in_its_own_emulation(emulation):
    assert current_emulation() is emulation and emulation.plants() == {}


def test_two_emulations_do_not_share_a_plant():
    clock = VirtualClock()
    spinning, idle = Emulation("spinning"), Emulation("idle")
    with use_emulation(spinning):
        fast = open_balance(clock)
        spinning.plant("fig525").set_duty(0.5, clock.now())
    with use_emulation(idle):
        still = open_balance(clock)
    clock.sleep(3.0)
    # the balance of the spinning emulation carries the PFR force; the other one nothing
    assert fast.read_stable().value > 1e-3 and abs(still.read_stable().value) < 1e-5
    assert spinning.plant("fig525") is not idle.plant("fig525")
    fast.close()
    still.close()


def test_nested_emulations_restore_the_outer_one(emulation):
    with use_emulation() as inner:
        assert current_emulation() is inner
    assert current_emulation() is emulation
