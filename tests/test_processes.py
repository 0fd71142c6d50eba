"""labkit.testing.processes: a wrapper and the child it starts both end (the rerun leak), and
the environment marker finds an orphan."""

from __future__ import annotations

import os
import subprocess
import sys
import time

from labkit.testing.processes import processes_with_env, start_group, stop_group

WRAPPER = "import subprocess, sys; subprocess.call([sys.executable, '-c', 'import time; time.sleep(120)'])"


def test_stop_group_ends_the_wrapper_and_its_child():
    marker = f"test-{os.getpid()}-group"
    env = {**os.environ, "LABKIT_PROCESS_TEST": marker}
    proc = start_group([sys.executable, "-c", WRAPPER], env=env, stdout=subprocess.DEVNULL)
    try:
        while len(processes_with_env("LABKIT_PROCESS_TEST", marker)) < 2:   # wrapper + child up
            time.sleep(0.01)
    finally:
        stop_group(proc)
    assert processes_with_env("LABKIT_PROCESS_TEST", marker) == {}


def test_terminate_alone_leaves_the_child_and_the_marker_finds_it():
    marker = f"test-{os.getpid()}-orphan"
    env = {**os.environ, "LABKIT_PROCESS_TEST": marker}
    proc = start_group([sys.executable, "-c", WRAPPER], env=env, stdout=subprocess.DEVNULL)
    try:
        while len(processes_with_env("LABKIT_PROCESS_TEST", marker)) < 2:
            time.sleep(0.01)
        proc.terminate()
        proc.wait(timeout=10)
        left = processes_with_env("LABKIT_PROCESS_TEST", marker)
        assert len(left) == 1 and "time.sleep(120)" in next(iter(left.values()))
    finally:
        stop_group(proc)
    assert processes_with_env("LABKIT_PROCESS_TEST", marker) == {}
