"""Where the strobe analysis spends its time (issue 26, item 5; docs/explanation/strobe-speed.md).

Draws one clip with the independent renderer (labkit.testing.strobe_cylinder), analyses it under
cProfile with the process's CPU clock (every thread), prints the result against the truth and the
functions that took the most time.

    python analysis/strobe_speed_profile.py --body large --room-light 0.5 --size 640x480
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from labkit.testing.strobe_cylinder import sized, write_clip
from labkit.vision.strobe.analyse import analyse_strobe


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--body", choices=["small", "medium", "large"], default="large")
    parser.add_argument("--room-light", type=float, default=0.5, help="over one exposure's flash light")
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    clip = replace(sized(args.body, (w, h), room_light=args.room_light), frames=args.frames)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_clip(clip, Path(tmp) / "clip.avi")
        profile = cProfile.Profile(time.process_time)
        cpu = time.process_time()
        profile.enable()
        r = analyse_strobe(path, rotor_hz=clip.rotor_hz, strobe_hz=clip.strobe_hz)
        profile.disable()
        cpu = time.process_time() - cpu
    truth = clip.truth()
    print(f"{args.size} {args.body} body {clip.extent_px()[0]:.0f}x{clip.extent_px()[1]:.0f} px, room light "
          f"{args.room_light / (1 + args.room_light):.0%} of the light, {clip.duration_s:.1f} s clip: "
          f"{cpu:.2f} CPU-s ({cpu / clip.duration_s:.2f}x the clip)")
    print(f"tilt {r.tilt_amplitude_rad:.4f} rad (truth {truth['tilt_amplitude_rad']:.4f}), lateral "
          f"{r.lateral_amplitude_px:.2f} px (truth {truth['lateral_amplitude_px']:.2f}), verdict "
          f"{r.quality.verdict}; room-light model: {r.quality.evidence['room_light_model']}")
    pstats.Stats(profile).sort_stats("cumtime").print_stats(args.top)


if __name__ == "__main__":
    main()
