"""The vision verdicts the suite compares across floating-point paths (test_fp_paths.py).

Run as a script (``python fp_path_cases.py OUT.json``) in a process whose environment chooses the
BLAS kernel (``OPENBLAS_CORETYPE``) and OpenCV's SIMD (``OPENCV_CPU_DISABLE``); writes, per case,
the verdict and the numbers a user reads. The cases: the committed example clips, and the
strobe scenes whose verdicts hang on an iterative fit (room light, rolling-shutter bands), drawn
by the independent renderer of tests/vision/strobe_scenes.py.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
VIDEOS = HERE.parents[1] / "recordings" / "videos"
SCREEN_MM, MM_PER_PX = 500.0, 0.4


def laser_case(name: str) -> dict:
    from labkit.vision.laser.analyse import analyse_laser

    r = analyse_laser(str(VIDEOS / name), screen_distance_mm=SCREEN_MM, mm_per_px=MM_PER_PX)
    p = r.pattern
    numbers = {"tilt_major_rad": r.tilt_rad.major, "centre_x_px": p.center_px[0],
               "centre_y_px": p.center_px[1]}
    return {"verdict": r.quality.verdict, "reasons": list(r.quality.reasons), "type": p.type,
            "loops": p.loops, "numbers": numbers}


def strobe_case(path: str, rotor_hz: float, strobe_hz: float) -> dict:
    from labkit.vision.strobe.analyse import analyse_strobe

    r = analyse_strobe(path, rotor_hz=rotor_hz, strobe_hz=strobe_hz)
    room = r.room_light
    return {"verdict": r.quality.verdict, "reasons": list(r.quality.reasons),
            "room_light_settled": None if room is None else room.settled,
            "numbers": {"tilt_amplitude_rad": r.tilt_amplitude_rad,
                        "lateral_amplitude_px": r.lateral_amplitude_px,
                        "room_light_fraction": 0.0 if room is None else room.fraction_of_light}}


def all_cases() -> dict:
    sys.path.insert(0, str(HERE))
    from strobe_scenes import Scene, write

    out = {name: laser_case(name) for name in ("laser-ellipse-medium.mp4", "laser-epitrochoid4-hard.mp4")}
    spec = json.loads((VIDEOS / "strobe-medium.truth.json").read_text())["spec"]
    out["strobe-medium.mp4"] = strobe_case(str(VIDEOS / "strobe-medium.mp4"), spec["rotor_hz"],
                                           spec["strobe_hz"])
    scenes = {"room-light-40pct": Scene(ghost=0.4, seed=10),
              "rolling-shutter-bands": Scene(readout_s=0.02, rest_deg=80.0, seed=6)}
    with tempfile.TemporaryDirectory() as folder:
        for name, scene in scenes.items():
            out[name] = strobe_case(write(scene, Path(folder) / f"{name}.avi"), scene.rotor_hz,
                                    scene.strobe_hz)
    return out


if __name__ == "__main__":
    Path(sys.argv[1]).write_text(json.dumps(all_cases(), indent=1))
