"""What labkit serves listens on 127.0.0.1 unless asked (issue 17, item 11): the spawned rerun
viewer, checked on the real rerun binary through the kernel's own socket table."""

from __future__ import annotations

import os
import socket
import stat
import sys
from pathlib import Path

import pytest

from labkit.stream import parse_rerun_spec
from labkit.stream.viewer import rerun_executable, spawn_viewer, start_rerun, wait_listening

pytestmark = pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="reads Linux /proc/net/tcp")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def listen_addresses(port: int) -> set[str]:
    """Local IPv4 addresses with a listening TCP socket on ``port`` (from /proc/net/tcp)."""
    found = set()
    for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        address, port_hex = local.split(":")
        if state == "0A" and int(port_hex, 16) == port:  # 0A = LISTEN
            found.add(socket.inet_ntoa(bytes.fromhex(address)[::-1]))
    return found


def end(process) -> None:
    process.terminate()
    try:
        process.wait(timeout=10)
    except Exception:  # noqa: BLE001 - make sure it is gone
        process.kill()
        process.wait(timeout=10)


def test_a_rerun_server_labkit_starts_listens_on_localhost_only():
    port = free_port()
    server = start_rerun("--serve-grpc", port=port)
    try:
        wait_listening(port, server)
        assert listen_addresses(port) == {"127.0.0.1"}
    finally:
        end(server)
    assert server.poll() is not None  # the process started is the one that listened: gone now


def test_spawned_viewer_binds_localhost_and_spawn_address_is_explicit(tmp_path, monkeypatch):
    # the real binary, told to serve gRPC only (no display here), with exactly labkit's viewer argv
    wrapper = tmp_path / "rerun-headless"
    wrapper.write_text(f"#!/bin/sh\nexec {rerun_executable()} --serve-grpc \"$@\"\n")
    wrapper.chmod(wrapper.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("RERUN_CLI_PATH", str(wrapper))
    port = free_port()
    url = spawn_viewer(port=port)
    try:
        assert url == f"rerun+http://127.0.0.1:{port}/proxy"
        assert listen_addresses(port) == {"127.0.0.1"}
    finally:
        pids = [p for p in os.listdir("/proc") if p.isdigit()]
        for pid in pids:  # the detached viewer: find it by its --port argument and end it
            try:
                argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
            except OSError:
                continue
            if str(port).encode() in argv and b"--serve-grpc" in argv:
                os.kill(int(pid), 15)
                try:
                    os.waitpid(int(pid), 0)  # our child (detached into its own session): reap it
                except ChildProcessError:
                    pass
    assert parse_rerun_spec("spawn").target == ""
    assert parse_rerun_spec("spawn:0.0.0.0").target == "0.0.0.0"


def test_python_m_rerun_is_not_what_labkit_starts():
    # `python -m rerun` runs the binary as a child, which terminate() would leave listening
    assert Path(rerun_executable()).name.startswith("rerun")
    assert not rerun_executable().endswith(".py") and rerun_executable() != sys.executable
