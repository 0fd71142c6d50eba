"""Suite-wide fixtures.

Each test runs in its own emulation (:class:`labkit.emulators.Emulation`): the plants of its
``sim://`` ports are its own, so no test sees the motors or forces another left behind, and
no test resets a registry by hand.

Every process a test starts must be ended by that test: a session
that leaves one running (a ``rerun`` server, an emulator host, a ``labkit`` subprocess) fails,
naming its command line.

Processes are recognised by an environment marker set here before any test runs; children
inherit it, also when they are orphaned (reparented to init) or start their own session."""

from __future__ import annotations

import os
import time
import uuid

import pytest

from labkit.emulators import Emulation, use_emulation
from labkit.testing.processes import processes_with_env

MARKER = "LABKIT_TEST_SESSION"
os.environ[MARKER] = f"{os.getpid()}-{uuid.uuid4().hex}"

#: a process that was just ended may need a moment to disappear from /proc
GRACE_S = 5.0


def leftover_processes() -> dict[int, str]:
    return processes_with_env(MARKER, os.environ[MARKER], exclude={os.getpid()})


@pytest.fixture(scope="session", autouse=True)
def no_process_left_behind():
    yield
    deadline = time.monotonic() + GRACE_S
    left = leftover_processes()
    while left and time.monotonic() < deadline:
        time.sleep(0.1)
        left = leftover_processes()
    if left:
        for pid in left:
            try:
                os.kill(pid, 9)   # do not leave them to the next session either
            except OSError:
                pass
        lines = "\n".join(f"  pid {pid}: {cmd}" for pid, cmd in sorted(left.items()))
        pytest.fail(f"the test session left {len(left)} process(es) running:\n{lines}", pytrace=False)


@pytest.fixture(autouse=True)
def emulation(request):
    """The test's own emulation (``emulation.plant("fig525")`` is what its sim:// ports share)."""
    with use_emulation(Emulation(request.node.nodeid)) as emu:
        yield emu
