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


def test_bench_camera_prints_one_row_per_size_and_rate():
    import json
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "labkit", "bench", "camera", "--seconds", "0.1", "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    rows = [json.loads(line) for line in done.stdout.splitlines()]
    assert [(r["size"], r["fps"]) for r in rows] == [("320x240", 30.0), ("320x240", 60.0),
                                                    ("640x480", 30.0), ("640x480", 60.0)]
    assert all(r["ratio"] > 0 and r["bytes_per_frame"] > 0 and r["frames"] >= 3 for r in rows)
    assert all(r["cpu_s"] > 0 and r["cpu_ratio"] > 0 and r["load_average"] >= 0 for r in rows)
