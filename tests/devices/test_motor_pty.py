"""Motor drivers against their emulators on real pseudo-terminals with a real clock: the
keep-alive runs on its own thread, close commands zero, an unplug is a clear error."""

from __future__ import annotations

import pytest

from labkit.devices.registry import driver_class
from labkit.emulators.plant import shared_plant
from labkit.emulators.sim_port import build_emulator
from labkit.errors import DeviceDisconnected
from labkit.io.clock import RealClock
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost

pytestmark = pytest.mark.timeout(30)


def open_on_pty(host: PtyHost, protocol: str, clock: RealClock, **options):
    cls = driver_class("motor", protocol)
    port = open_port(host.path, clock=clock, timeout=0, **cls.default_serial)
    # a generous reply timeout: a loaded CI box may starve the in-process emulator for a while
    return cls(port, clock, name=f"motor on {host.path}", **{"reply_timeout_s": 2.0, **options})


def wait_until(predicate, clock: RealClock, timeout_s: float = 10.0) -> bool:
    """Event-driven wait on the emulator's state (True as soon as it holds)."""
    end = clock.now() + timeout_s
    while not predicate():
        if clock.now() > end:
            return False
        clock.sleep(0.005)
    return True


@pytest.mark.parametrize("protocol, query", [
    ("pololu_smc", "command_timeout_ms=200"),
    ("esc_bridge", "arm_s=0"),
    ("vesc", "timeout_ms=200"),
])
def test_motor_over_a_pty_keeps_alive_and_stops_on_close(protocol, query):
    clock = RealClock()
    emulator = build_emulator(f"sim://{protocol}?plant=pty&{query}")
    plant = shared_plant("pty")
    with PtyHost(emulator, clock=clock) as host:
        motor = open_on_pty(host, protocol, clock)
        motor.identify()
        motor.enable()
        motor.set_duty(0.3)
        clock.sleep(0.6)    # three times the controller's command timeout
        status = motor.status()
        assert status.duty == pytest.approx(0.3, abs=1e-3) and not status.errors
        assert plant.motor("rotor").duty == pytest.approx(0.3, abs=1e-3)
        motor.close()
        assert wait_until(lambda: plant.motor("rotor").duty == 0.0, clock)   # the STOP arrived


def test_unplugged_motor_controller_is_a_clear_error_and_stop_is_quiet():
    clock = RealClock()
    emulator = build_emulator("sim://pololu_smc?plant=pty")
    with PtyHost(emulator, clock=clock) as host:
        motor = open_on_pty(host, "pololu_smc", clock)
        motor.enable()
        motor.set_duty(0.2)
        host.unplug()   # the cable is pulled while the motor runs (not at a clock time after open)
        assert wait_until(lambda: not host.connected, clock)
        with pytest.raises(DeviceDisconnected) as info:
            motor.status()
        assert host.paths[0] in str(info.value)
        motor.close()    # must not raise on the dead port
