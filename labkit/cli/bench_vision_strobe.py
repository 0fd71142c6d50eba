"""The strobe part of ``labkit bench vision`` (issue 26, item 5; docs/explanation/strobe-speed.md):
is a strobe burst analysed faster than it was filmed?

Clips are drawn by :mod:`labkit.testing.strobe_cylinder` (its own geometry, not ``labkit.footage``
nor ``labkit.synth``): a strobe-lit cylinder, small and large for the frame, with and without room
light, at each size asked for, written as MJPEG. Each clip is analysed in a fresh process (so its
peak memory is its own, read from ``wait4``); the process times the analysis alone (imports apart)
with :func:`time.process_time` (every thread's CPU) and the wall clock. Printed per clip: the
ratios CPU time / clip duration and wall time / clip duration, the peak resident memory, and the
errors of tilt and lateral amplitude against the renderer's truth.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

BODIES = ("small", "large")
ROOM_LIGHTS = (0.0, 0.5)  # room light over one exposure's flash light (0.5: a third of all the light)

CHILD = """
import json, sys, time
from labkit.vision.strobe.analyse import analyse_strobe
path, rotor, strobe = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
cpu, wall = time.process_time(), time.perf_counter()
r = analyse_strobe(path, rotor_hz=rotor, strobe_hz=strobe)
cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
room = r.room_light
print(json.dumps({"cpu_s": cpu, "wall_s": wall, "tilt": r.tilt_amplitude_rad,
                  "lateral": r.lateral_amplitude_px, "verdict": r.verdict,
                  "ghost": r.quality.evidence["ghost_fraction"],
                  "room": None if room is None else room.fraction_of_light}))
"""


def analyse_in_child(path: str, rotor_hz: float, strobe_hz: float) -> dict:
    """Analyse ``path`` in a fresh Python; the child's numbers plus its peak RSS (MB)."""
    proc = subprocess.Popen([sys.executable, "-c", CHILD, path, repr(rotor_hz), repr(strobe_hz)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.stdout is not None
    out = proc.stdout.read()  # warnings and the JSON line, in one pipe (no deadlock on a full one)
    _, status, usage = os.wait4(proc.pid, 0)  # the child's own peak memory
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError(f"analysis of {path} failed (exit {proc.returncode}): {out.strip()[-400:]}")
    result = json.loads(out.strip().splitlines()[-1])
    result["peak_mb"] = usage.ru_maxrss / 1024  # kB on Linux
    return result


def strobe_rows(sizes: list[tuple[int, int]], frames: int, folder: Path, log=print) -> list[dict]:
    """Render and analyse every clip; one row per clip (also printed as it comes)."""
    from labkit.testing.strobe_cylinder import sized, write_clip

    rows = []
    for size in sizes:
        for body in BODIES:
            for room in ROOM_LIGHTS:
                clip = replace(sized(body, size, room_light=room), frames=frames)
                path = write_clip(clip, folder / f"strobe-{size[0]}x{size[1]}-{body}-room{room:g}.avi")
                got = analyse_in_child(path, clip.rotor_hz, clip.strobe_hz)
                truth = clip.truth()
                length, width = clip.extent_px()
                seconds = clip.duration_s
                row = {"size": f"{size[0]}x{size[1]}", "body": f"{body} {length:.0f}x{width:.0f} px",
                       "room_light": room / (1 + room), "duration_s": seconds, **got,
                       "cpu_ratio": got["cpu_s"] / seconds, "wall_ratio": got["wall_s"] / seconds,
                       "tilt_error": got["tilt"] / truth["tilt_amplitude_rad"] - 1,
                       "lateral_error_px": got["lateral"] - truth["lateral_amplitude_px"],
                       "lateral_truth_px": truth["lateral_amplitude_px"]}
                rows.append(row)
                log(format_row(row))
    return rows


HEADER = (f"{'clip':10s} {'body':22s} {'room':>5s} {'cpu s':>6s} {'cpu/dur':>7s} {'wall s':>6s} "
          f"{'wall/dur':>8s} {'peak MB':>7s}  {'tilt err':>8s} {'lateral err':>16s}  verdict")


def format_row(r: dict) -> str:
    lateral = f"{r['lateral_error_px']:+.2f} px ({100 * r['lateral_error_px'] / r['lateral_truth_px']:+.1f}%)"
    return (f"{r['size']:10s} {r['body']:22s} {r['room_light']:5.0%} {r['cpu_s']:6.2f} "
            f"{r['cpu_ratio']:6.2f}x "
            f"{r['wall_s']:6.2f} {r['wall_ratio']:7.2f}x {r['peak_mb']:7.0f}  {100 * r['tilt_error']:+7.2f}% "
            f"{lateral:>16s}  {r['verdict']}")


def run_strobe(sizes: list[tuple[int, int]], frames: int, keep: str | None) -> int:
    """Print the strobe table; 0 when every clip was analysed."""
    print(f"strobe: {frames} frames at 30 fps per clip (independent renderer labkit.testing.strobe_cylinder, "
          "MJPEG); each analysed in a fresh process")
    print("cpu = process time of the analysis (all threads, imports apart); ratio = time / clip duration; "
          "room = room light's share of all the light")
    print(HEADER)
    with tempfile.TemporaryDirectory(prefix="labkit-bench-strobe-") as tmp:
        folder = Path(keep) if keep else Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        rows = strobe_rows(sizes, frames, folder)
    worst = max(rows, key=lambda r: r["cpu_ratio"])
    print(f"slowest: {worst['size']} {worst['body']} room {worst['room_light']:.0%}: "
          f"{worst['cpu_ratio']:.2f}x the clip's duration in CPU time; "
          f"peak memory {max(r['peak_mb'] for r in rows):.0f} MB")
    return 0
