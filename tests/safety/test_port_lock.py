"""Exclusive ports (issue 17, item 8): one process per serial device; the lock names its holder
and goes with it, however it ends (SIGKILL too)."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

from labkit.emulators.sim_port import build_emulator
from labkit.io.clock import RealClock
from labkit.io.port_lock import PortBusy, device_path
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost

pytestmark = [pytest.mark.skipif(sys.platform == "win32", reason="flock"), pytest.mark.timeout(60)]

HOLD = "from labkit.io.ports import open_port; import sys, time; p = open_port(sys.argv[1]); " \
       "print('open', flush=True); time.sleep(60)"


def test_a_second_opener_is_refused_naming_the_holder_until_the_holder_is_killed():
    with PtyHost(build_emulator("sim://mtsics"), clock=RealClock()) as host:
        holder = subprocess.Popen([sys.executable, "-c", HOLD, host.path], stdout=subprocess.PIPE, text=True)
        try:
            assert holder.stdout.readline().strip() == "open"
            with pytest.raises(PortBusy) as busy:
                open_port(host.path, timeout=0.1)
            assert f"{host.path}: port busy, held by PID {holder.pid}" in str(busy.value)
            holder.send_signal(signal.SIGKILL)
            holder.wait(timeout=10)
            port = open_port(host.path, timeout=0.1)   # the kernel dropped the lock with its holder
            port.close()
            port.close()                               # a second close releases nothing twice
            again = open_port(host.path, timeout=0.1)  # closing released it in this process too
            again.close()
        finally:
            if holder.poll() is None:
                holder.kill()
                holder.wait(timeout=10)
            holder.stdout.close()


def test_only_serial_devices_are_locked():
    assert device_path("sim://mtsics") is None
    assert device_path("socket://127.0.0.1:9") is None
    assert device_path("/nonexistent/ttyUSB9") is None
    assert device_path("/dev/null") == "/dev/null"   # a character device: would be locked
