"""Opening a rerun recording from a ``--rerun`` spec: ``spawn``, ``connect[:ADDR]``, ``save:FILE``.

* ``save:FILE`` writes an .rrd file (works anywhere, the CI default for tests).
* ``connect`` / ``connect:ADDR`` streams to a running viewer over gRPC; the default address
  is the viewer's on localhost (``rerun+http://127.0.0.1:9876/proxy``); ``ADDR`` may be
  ``HOST:PORT`` or a full ``rerun+http://...`` URL. When nothing answers on that port, labkit
  says so and saves to the fallback file instead (as ``spawn`` without a display does).
* ``spawn`` starts a viewer listening on 127.0.0.1 only (``spawn:ADDRESS``, e.g.
  ``spawn:0.0.0.0``, to let other machines connect; see labkit.stream.viewer). With no
  display (no ``DISPLAY``/``WAYLAND_DISPLAY``) a viewer
  cannot start (docs/explanation/rerun-notes.md#no-display: it dies and ``spawn`` still blocks ~11 s), so
  labkit says so and saves to a fallback file instead, which ``rerun FILE`` opens later.
"""

from __future__ import annotations

import argparse
import os
import socket
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from labkit.errors import LabkitError

DEFAULT_CONNECT_URL = "rerun+http://127.0.0.1:9876/proxy"
#: how long ``connect`` waits for a viewer's port before it saves to a file instead (s)
CONNECT_PROBE_S = 2.0


@dataclass(frozen=True)
class RerunSpec:
    """A parsed ``--rerun`` value. ``mode`` is ``spawn``, ``connect`` or ``save``."""

    mode: str
    target: str = ""

    def describe(self) -> str:
        if self.mode == "save":
            return f"saved to {self.target} (open with: rerun {self.target})"
        if self.mode == "connect":
            return f"streamed to the viewer at {self.target}"
        return f"streamed to a spawned viewer (listening on {self.target or '127.0.0.1'})"


def parse_rerun_spec(text: str) -> RerunSpec:
    """Parse ``spawn | connect[:ADDR] | save:FILE``; raises LabkitError with the reason."""
    mode, _, rest = text.partition(":")
    if mode == "spawn":
        if not rest:
            return RerunSpec("spawn")
        from labkit.stream.viewer import check_bind_address

        try:
            return RerunSpec("spawn", check_bind_address(rest))
        except LabkitError as exc:
            raise LabkitError(f"--rerun {text}: {exc}") from None
    if mode == "connect":
        if not rest:
            return RerunSpec("connect", DEFAULT_CONNECT_URL)
        if rest.startswith("rerun+http") or "://" in rest:
            return RerunSpec("connect", rest)
        host, _, port = rest.rpartition(":")
        if not host:
            host, port = rest, "9876"
        if not port.isdigit():
            raise LabkitError(f"--rerun {text}: port {port!r} is not a number")
        return RerunSpec("connect", f"rerun+http://{host}:{port}/proxy")
    if mode == "save":
        if not rest:
            raise LabkitError("--rerun save:FILE needs a file name, e.g. save:run.rrd")
        return RerunSpec("save", rest)
    raise LabkitError(f"--rerun {text!r}: expected spawn, connect[:ADDR] or save:FILE")


def _rerun_spec_type(text: str) -> RerunSpec:
    try:
        return parse_rerun_spec(text)
    except LabkitError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_rerun_argument(parser: argparse.ArgumentParser) -> None:
    """Add the common ``--rerun spawn|connect[:ADDR]|save:FILE`` option to a sub-command."""
    parser.add_argument(
        "--rerun", type=_rerun_spec_type, default=None, metavar="SPEC",
        help="stream to rerun: spawn[:BIND_IP] (viewer on 127.0.0.1 by default) | "
             "connect[:HOST:PORT] | save:FILE.rrd",
    )


def has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def viewer_answers(url: str, timeout_s: float = CONNECT_PROBE_S) -> bool:
    """Whether something accepts a TCP connection at the host and port of a
    ``rerun+http://HOST:PORT/...`` URL (a viewer or ``rerun --serve-grpc``)."""
    from urllib.parse import urlsplit

    parts = urlsplit(url.replace("rerun+", "", 1))
    host, port = parts.hostname or "127.0.0.1", parts.port or 9876
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            return True
    except OSError:
        return False


def open_stream(spec: RerunSpec | str | None, app_id: str, *, recording_id: str | None = None,
                blueprint: Any = None, fallback_file: str | Path = "labkit.rrd") -> Any:
    """A ``rerun.RecordingStream`` for ``spec`` (None -> None: nothing is logged).

    Uses strict mode (bad log calls raise instead of being dropped) and no automatic
    ``log_time`` timeline, so the same run gives the same file. Close it with
    ``rec.disconnect()`` (writes the .rrd footer) or use it as a context manager.
    """
    if spec is None:
        return None
    if isinstance(spec, str):
        spec = parse_rerun_spec(spec)
    import rerun as rr

    rr.set_strict_mode(True)
    rec = rr.RecordingStream(app_id, recording_id=recording_id)
    rec.set_log_time_enabled(False)
    if spec.mode == "save":
        path = Path(spec.target)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise LabkitError(f"--rerun save:{path}: cannot create folder ({exc.strerror})") from None
        rec.save(str(path), default_blueprint=blueprint)
    elif spec.mode == "connect" and viewer_answers(spec.target):
        rec.connect_grpc(spec.target, default_blueprint=blueprint)
    elif spec.mode == "connect":
        print(f"labkit: no rerun viewer answers at {spec.target}; saving to {fallback_file} instead "
              f"(open it with: rerun {fallback_file})", file=sys.stderr)
        rec.save(str(fallback_file), default_blueprint=blueprint)
    elif has_display():
        from labkit.stream.viewer import LOCALHOST, spawn_viewer

        # not rec.spawn(): that viewer listens on 0.0.0.0 (rerun-sdk 0.41)
        rec.connect_grpc(spawn_viewer(spec.target or LOCALHOST), default_blueprint=blueprint)
    else:
        print(f"labkit: no display for a rerun viewer; saving to {fallback_file} instead "
              f"(open it with: rerun {fallback_file})", file=sys.stderr)
        rec.save(str(fallback_file), default_blueprint=blueprint)
    return rec
