"""Stop first, record second (issue 17, item 2): a cassette that cannot be written never keeps
a command off the wire, and what was written stays a valid cassette.

The disk is "full" through RLIMIT_FSIZE (writes past the limit fail with EFBIG, as they fail
with ENOSPC on a full disk), lowered around the one call and restored.
"""

from __future__ import annotations

import contextlib
import resource
import sys

import pytest

from labkit.devices.motor.pololu_smc import PololuSmc
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.io.cassette import load_cassette
from labkit.io.clock import VirtualClock, use_clock
from labkit.io.ports import open_port

pytestmark = pytest.mark.skipif(not hasattr(resource, "RLIMIT_FSIZE") or sys.platform == "win32",
                                reason="needs RLIMIT_FSIZE")


@contextlib.contextmanager
def disk_full_beyond(size: int):
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (size, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))


def test_stop_reaches_the_motor_when_the_cassette_cannot_be_written(tmp_path):
    reset_plants()
    cassette = tmp_path / "rotor_motor.jsonl"
    clock = VirtualClock()
    with use_clock(clock):
        port = open_port(f"record://sim://pololu_smc?plant=full&cassette={cassette}&port=rotor_motor",
                         clock=clock, baudrate=9600, timeout=0.2)
        motor = PololuSmc(port, clock, name="rotor_motor")
        motor.enable()
        motor.set_duty(0.5)
        clock.sleep(0.3)
        plant = shared_plant("full").motor("rotor")
        assert plant.duty == pytest.approx(0.5)
        with disk_full_beyond(cassette.stat().st_size):
            motor.stop()
        assert plant.duty == 0.0                       # the STOP went out all the same
        assert motor.stop_error is None                # ... and is not reported as failed
        assert port.record_error == f"cannot write {cassette}: File too large"
        motor.close()
    recorded = load_cassette(cassette)                # every line whole: still a valid cassette
    assert recorded.events and all(e["dir"] in ("tx", "rx", "ctl") for e in recorded.events)
    reset_plants()
