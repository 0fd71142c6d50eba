"""``--rerun connect:HOST:PORT`` end to end against a real rerun gRPC server (no viewer needed):
``rerun --serve-grpc`` is the proxy a viewer would be; a second ``rerun`` process subscribed to
it with ``--save`` writes what arrived to an .rrd, which is read back."""

from __future__ import annotations

import json
import socket
import subprocess
import time
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.stream.readback import column, entity_paths
from labkit.stream.viewer import start_rerun
from labkit.testing.processes import stop_group

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings" / "videos"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_listening(port: int, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise TimeoutError(f"nothing listens on port {port} after {timeout_s} s")


def rerun(*args: str, port: int) -> subprocess.Popen:
    """The rerun binary itself on 127.0.0.1 (``python -m rerun`` is a wrapper whose binary child
    outlived ``terminate()``), leading its own process group so :func:`stop_group` ends it whole."""
    return start_rerun(*args, port=port, detach=True)


@pytest.fixture
def grpc_server():
    port = free_port()
    server = rerun("--serve-grpc", port=port)
    try:
        wait_listening(port)
        yield port
    finally:
        stop_group(server)


@pytest.mark.filterwarnings("ignore:RRD file has no footer")  # read while the saver still writes
def test_laser_analysis_streams_to_a_running_server(grpc_server, tmp_path, capsys):
    out = tmp_path / "laser.json"
    clip = RECORDINGS / "laser-ellipse-medium.mp4"
    assert main(["analyse", "laser", str(clip), "--json", str(out),
                 "--rerun", f"connect:127.0.0.1:{grpc_server}"]) == 0
    frames_analysed = json.loads(out.read_text())["quality"]["frames_analysed"]
    saved = tmp_path / "received.rrd"
    saver = rerun(f"rerun+http://127.0.0.1:{grpc_server}/proxy", "--save", str(saved), port=free_port())
    try:  # the server buffers what it was sent for late subscribers; wait until all of it is saved
        deadline, frames = time.monotonic() + 30, []
        while time.monotonic() < deadline and len(frames) < frames_analysed:
            time.sleep(0.5)
            if saved.exists() and saved.stat().st_size:
                frames, _ = column(saved, "/video/frame", "EncodedImage:blob", "frame")
    finally:
        stop_group(saver)
    assert len(frames) == frames_analysed
    assert {"/video/frame", "/video/frame/fit", "/video/pattern"} <= entity_paths(saved)
