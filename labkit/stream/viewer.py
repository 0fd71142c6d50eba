"""Starting a rerun viewer (or a bare gRPC server) that listens on 127.0.0.1 unless asked.

``rerun.spawn()`` (rerun-sdk 0.41) starts the viewer with its default bind address,
``0.0.0.0``: anyone on the lab network could connect and read the run. labkit starts the
viewer binary itself with ``--bind 127.0.0.1`` (``--rerun spawn:ADDRESS`` asks for another
address) and then connects to it over gRPC, which is all ``rerun.spawn()`` does besides.

``python -m rerun`` is a wrapper that runs the binary as a *child*: terminating the wrapper
leaves the binary listening. :func:`rerun_executable` finds the binary itself, so the
process a caller starts is the one that listens (and the one it ends).
"""

from __future__ import annotations

import ipaddress
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

from labkit.errors import LabkitError

LOCALHOST = "127.0.0.1"
DEFAULT_VIEWER_PORT = 9876


def rerun_executable() -> str:
    """Path of the rerun binary shipped with rerun-sdk (``RERUN_CLI_PATH`` overrides it)."""
    override = os.environ.get("RERUN_CLI_PATH")
    if override:
        return override
    try:
        import rerun_cli
    except ImportError:  # pragma: no cover - rerun-sdk always ships rerun_cli
        raise LabkitError("the rerun viewer binary is not installed (pip install rerun-sdk)") from None
    binary = Path(rerun_cli.__file__).with_name("rerun" + (".exe" if sys.platform.startswith("win") else ""))
    if not binary.exists():
        raise LabkitError(f"the rerun viewer binary is missing: {binary}")
    return str(binary)


def check_bind_address(text: str) -> str:
    """An IP address to listen on (``127.0.0.1``, ``::1``, ``0.0.0.0`` ...) or LabkitError."""
    try:
        return str(ipaddress.ip_address(text))
    except ValueError:
        raise LabkitError(f"{text!r} is not an IP address to listen on (e.g. 127.0.0.1)") from None


def listening(port: int, host: str = LOCALHOST) -> bool:
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
        s.settimeout(0.5)
        return s.connect_ex((host, port)) == 0


def start_rerun(*args: str, port: int, bind: str = LOCALHOST, detach: bool = False,
                quiet: bool = True) -> subprocess.Popen:
    """Start the rerun binary with ``--port PORT --bind BIND`` and ``args``; not waited for."""
    out = subprocess.DEVNULL if quiet else None
    argv = [rerun_executable(), *args, "--port", str(port), "--bind", check_bind_address(bind)]
    return subprocess.Popen(argv, stdout=out, stderr=out, stdin=subprocess.DEVNULL,
                            start_new_session=detach)


def wait_listening(port: int, process: subprocess.Popen | None = None, timeout_s: float = 20.0,
                   host: str = LOCALHOST) -> None:
    """Return once something accepts connections on ``host:port``; LabkitError if the process
    exits first or nothing listens within ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if listening(port, host):
            return
        if process is not None and process.poll() is not None:
            raise LabkitError(f"the rerun viewer exited with status {process.returncode} before listening")
        time.sleep(0.1)
    raise LabkitError(f"nothing listens on {host}:{port} after {timeout_s:.0f} s")


def spawn_viewer(bind: str = LOCALHOST, port: int = DEFAULT_VIEWER_PORT, memory_limit: str = "25%") -> str:
    """Start a viewer listening on ``bind:port`` (unless one already listens there) and return
    the gRPC URL to connect to. The viewer outlives labkit, as with ``rerun.spawn()``."""
    host = LOCALHOST if bind in ("0.0.0.0", "::") else bind
    if not listening(port, host):
        process = start_rerun("--memory-limit", memory_limit, port=port, bind=bind, detach=True)
        wait_listening(port, process, host=host)
    return f"rerun+http://{host if ':' not in host else f'[{host}]'}:{port}/proxy"
