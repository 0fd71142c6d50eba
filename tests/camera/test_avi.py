"""The MJPEG AVI writer: the file holds the very JPEG bytes, and OpenCV reads every frame back at the
given rate (FFmpeg's JPEG decoder, not libjpeg's: pixels agree to > 35 dB PSNR, not exactly)."""

from __future__ import annotations

import cv2
import numpy as np

from labkit.devices.camera.avi import write_mjpeg_avi

from .loopback import numbered_jpeg


def test_avi_holds_the_jpegs_at_the_rate(tmp_path):
    jpegs = [numbered_jpeg(k) for k in range(7)]
    path = write_mjpeg_avi(tmp_path / "x.avi", jpegs, 25.0, (320, 240))
    data = path.read_bytes()
    at = 0
    for jpeg in jpegs:  # in order, unchanged
        at = data.index(jpeg, at) + len(jpeg)
    cap = cv2.VideoCapture(str(path))
    assert cap.get(cv2.CAP_PROP_FPS) == 25.0 and cap.get(cv2.CAP_PROP_FRAME_COUNT) == 7
    for jpeg in jpegs:
        ok, frame = cap.read()
        assert ok
        libjpeg = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
        assert cv2.PSNR(frame, libjpeg) > 35  # chroma upsampling differs at sharp red edges
    assert not cap.read()[0]
