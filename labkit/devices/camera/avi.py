"""A minimal AVI (RIFF) writer for JPEG frames, byte for byte: the analysis of a burst reads the
camera's own JPEGs at the camera's frame rate, with no re-encoding (OpenCV's VideoWriter would
decode and encode them again). One MJPG video stream and an ``idx1`` index (Microsoft's AVI RIFF
layout: ``hdrl`` with ``avih``/``strh``/``strf``, ``movi`` with ``00dc`` chunks)."""

from __future__ import annotations

import struct
from collections.abc import Sequence
from pathlib import Path


def _chunk(fourcc: bytes, data: bytes) -> bytes:
    pad = b"\0" if len(data) % 2 else b""
    return fourcc + struct.pack("<I", len(data)) + data + pad


def _list(kind: bytes, body: bytes) -> bytes:
    return b"LIST" + struct.pack("<I", len(body) + 4) + kind + body


def mjpeg_avi(jpegs: Sequence[bytes], fps: float, size: tuple[int, int]) -> bytes:
    """The AVI file holding ``jpegs`` as frames at ``fps`` (``size`` = (width, height))."""
    if not jpegs:
        raise ValueError("an AVI needs at least one frame")
    w, h = size
    n = len(jpegs)
    biggest = max(len(j) for j in jpegs)
    scale, rate = 1000, max(1, round(fps * 1000))
    avih = struct.pack("<14I", round(1e6 / fps), biggest * int(fps + 1), 0, 0x10, n, 0, 1, biggest, w, h,
                       0, 0, 0, 0)
    strh = b"vidsMJPG" + struct.pack("<IHHIIIIIIIIhhhh", 0, 0, 0, 0, scale, rate, 0, n, biggest,
                                     0xFFFFFFFF, 0, 0, 0, w, h)
    strf = struct.pack("<IiiHH4sIiiII", 40, w, h, 1, 24, b"MJPG", w * h * 3, 0, 0, 0, 0)
    strl = _list(b"strl", _chunk(b"strh", strh) + _chunk(b"strf", strf))
    hdrl = _list(b"hdrl", _chunk(b"avih", avih) + strl)
    movi_body = bytearray()
    index = bytearray()
    for jpeg in jpegs:
        index += b"00dc" + struct.pack("<III", 0x10, len(movi_body) + 4, len(jpeg))
        movi_body += _chunk(b"00dc", jpeg)
    body = b"AVI " + hdrl + _list(b"movi", bytes(movi_body)) + _chunk(b"idx1", bytes(index))
    return b"RIFF" + struct.pack("<I", len(body)) + body


def write_mjpeg_avi(path: str | Path, jpegs: Sequence[bytes], fps: float, size: tuple[int, int]) -> Path:
    """Write :func:`mjpeg_avi` to ``path``; returns the path."""
    p = Path(path)
    p.write_bytes(mjpeg_avi(jpegs, fps, size))
    return p
