"""``labkit bench camera``: does live laser analysis keep pace with capture? (issue 25, item 6)

For bursts of one second at 320x240 and 640x480, 30 and 60 fps, the emulated camera
(``sim://camera``, the model plant's motor driven open loop towards ``--rpm``) films the laser
trace on a virtual clock; the burst's JPEG bytes are wrapped in an AVI (no re-encoding) and
:func:`labkit.vision.laser.analyse.analyse_laser` runs on it, as ``cone-sweep`` does at every step.
Printed per case: the analysis wall time over the burst's duration (goal: at most 1.0, so
analysis in a worker keeps up with the camera), the same for the process's CPU time (all its
threads: what the analysis costs whatever else the machine runs; wall time on a loaded machine
waits for the cores), the rendering time per frame (the emulator's cost, not a camera's) and the
stored bytes per frame. The header gives the load average: ratios measured at a load above the
core count are the machine's, not the analysis's. ``--halves`` times what a ``cone-sweep`` step
does with its default ``halves=true``: the burst, then its odd and its even frames (the
stderr), about twice the work.
The first analysis of a process pays about a second of imports; it runs once before timing.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from typing import Any

CASES = (((320, 240), 30.0), ((320, 240), 60.0), ((640, 480), 30.0), ((640, 480), 60.0))


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("camera", help="laser analysis time / burst duration (goal <= 1.0) per size and rate")
    p.add_argument("--rpm", type=float, default=7000.0, help="rotor speed of the model plant (default 7000)")
    p.add_argument("--seconds", type=float, default=1.0, help="burst duration (default 1 s)")
    p.add_argument("--halves", action="store_true",
                   help="also analyse the odd and even frames apart, as cone-sweep does by default")
    p.add_argument("--json", action="store_true", help="one JSON object per case instead of a table")
    p.set_defaults(func=main)


def burst(size: tuple[int, int], fps: float, rpm: float, seconds: float) -> tuple[list[Any], float]:
    """A burst from the emulated camera with the rotor held at ``rpm``; (frames, render s/frame)."""
    import math

    from labkit.devices.camera import open_camera
    from labkit.emulators import Emulation, use_emulation
    from labkit.io.clock import VirtualClock

    with use_emulation(Emulation("bench-camera")) as emu:
        clock = VirtualClock()
        plant = emu.plant("model-fig525")
        # open loop, near the speed asked for (the drag of the model motor makes it a little lower)
        plant.set_duty(min(1.0, rpm * math.pi / 30.0 / plant.motor().max_speed_rad_s), 0.0)
        clock.sleep(5.0)  # ten time constants: the burst, not the ramp, is measured
        mm_per_px = 2.0 * 320 / size[0]
        camera = open_camera(f"sim://camera?seed=1&size={size[0]}x{size[1]}&fps={fps:g}&exposure_s=0.004"
                             f"&mm_per_px={mm_per_px:g}", clock)
        start = time.perf_counter()
        frames = camera.burst(max(2, round(fps * seconds)))
        render = (time.perf_counter() - start) / len(frames)
        camera.close()
    return frames, render


def analyse(frames: list[Any], fps: float, size: tuple[int, int], mm_per_px: float,
            halves: bool = False) -> tuple[float, float, dict]:
    """(wall s, CPU s, result) of a burst's analysis (and of its halves' with ``halves``)."""
    from labkit.protocols.cone_sweep import burst_cone_angle

    start, cpu = time.perf_counter(), time.process_time()
    result = burst_cone_angle(frames, fps, size, 500.0, mm_per_px)
    if halves:
        for k in (0, 1):
            burst_cone_angle(frames[k::2], fps / 2, size, 500.0, mm_per_px)
    return time.perf_counter() - start, time.process_time() - cpu, result


def main(args: argparse.Namespace) -> int:
    rows = []
    warm, _ = burst((320, 240), 30.0, args.rpm, 0.2)
    analyse(warm, 30.0, (320, 240), 2.0)
    for size, fps in CASES:
        frames, render = burst(size, fps, args.rpm, args.seconds)
        duration = len(frames) / fps
        wall, cpu, result = analyse(frames, fps, size, 2.0 * 320 / size[0], args.halves)
        rows.append({"size": f"{size[0]}x{size[1]}", "fps": fps, "frames": len(frames), "halves": args.halves,
                     "analysis_s": round(wall, 3), "ratio": round(wall / duration, 3),
                     "cpu_s": round(cpu, 3), "cpu_ratio": round(cpu / duration, 3),
                     "load_average": round(os.getloadavg()[0], 2),
                     "render_ms_per_frame": round(render * 1e3, 1),
                     "bytes_per_frame": round(sum(len(f.payload) for f in frames) / len(frames)),
                     "verdict": result["verdict"]})
    if args.json:
        for row in rows:
            print(json.dumps(row))
        return 0
    what = "whole burst + odd + even frames (cone-sweep's halves)" if args.halves else "whole burst"
    print(f"laser analysis ({what}) of {args.seconds:g} s bursts from sim://camera at {args.rpm:.0f} RPM "
          "(ratio = analysis time / burst duration; goal <= 1.0)")
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores"
          + (" (loaded: wall-time ratios wait for the cores; see the CPU ratio)"
             if os.getloadavg()[0] > (os.cpu_count() or 1) else ""))
    print(f"{'size':>8} {'fps':>4} {'frames':>6} {'analysis s':>10} {'ratio':>6} {'CPU s':>6} "
          f"{'CPU ratio':>9} {'render ms/f':>11} {'bytes/f':>8} verdict")
    for r in rows:
        print(f"{r['size']:>8} {r['fps']:>4.0f} {r['frames']:>6} {r['analysis_s']:>10.3f} {r['ratio']:>6.2f} "
              f"{r['cpu_s']:>6.2f} {r['cpu_ratio']:>9.2f} {r['render_ms_per_frame']:>11.1f} "
              f"{r['bytes_per_frame']:>8} {r['verdict']}")
    return 0


