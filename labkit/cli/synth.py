"""``labkit synth {laser,strobe,testset}``: write realistic synthetic footage with its ground truth
(``OUT`` plus ``OUT-stem.truth.json``), to test analysis or check a camera set-up before filming.

A photo suffix (.png, .jpg, ...) writes one long-exposure image (the brightest value of all frames).
``labkit synth laser OUT --angles RUN.csv`` renders a simulator run: columns ``t_s, tilt_x_rad,
tilt_y_rad`` (header optional; or an .npz/.npy with those three arrays/columns).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from labkit.cli.numbers import number
from labkit.cli.output import add_json_argument, write_json
from labkit.cli.parsers import command_parser
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import VideoError

if TYPE_CHECKING:  # numpy loads when a clip is written, not for --help
    import numpy as np


def _progress(frames: Iterator[np.ndarray], out: str | Path, total: int) -> Iterator[np.ndarray]:
    """``frames`` passed through, with a progress line on stderr every 2 s once rendering has
    taken 2 s (a long clip: ``labkit synth: z.mp4: 120 of 600 frames (2 s so far)``)."""
    from labkit.cli.progress import ProgressLines

    progress = ProgressLines(f"labkit synth: {out}", "frames")
    for done, frame in enumerate(frames, start=1):
        yield frame
        progress(done, total)


def _written(path: Path, truth: dict | None) -> dict:
    """``{"video", "truth", "ground_truth"}`` of one written clip (the ``--json`` document)."""
    from labkit.synth.writer import truth_path

    return {"video": str(path), "truth": str(truth_path(path)), "ground_truth": truth}


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError("expected WIDTHxHEIGHT, e.g. 640x480") from None
    if w < 32 or h < 32 or w > 7680 or h > 4320:
        raise argparse.ArgumentTypeError("size must be between 32x32 and 7680x4320")
    return w, h


def _bgr(text: str) -> tuple[float, float, float]:
    try:
        b, g, r = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError("expected B,G,R factors, e.g. 0.7,0.88,1") from None
    if min(b, g, r) < 0:
        raise argparse.ArgumentTypeError("colour factors must be >= 0")
    return b, g, r


def register(sub: argparse._SubParsersAction) -> None:
    parser = command_parser(sub, "synth", COMMAND_SUMMARIES["synth"],
                            __doc__)
    kinds = parser.add_subparsers(dest="kind", metavar="KIND")

    laser = kinds.add_parser("laser", help="laser trace on a screen")
    laser.add_argument("out", help="output .mp4/.avi/.mkv video or .png/.jpg photo")
    laser.add_argument(
        "--pattern", choices=["circle", "ellipse", "epitrochoid", "hypotrochoid"], default="circle"
    )
    laser.add_argument(
        "--level",
        choices=["easy", "medium", "hard"],
        default="medium",
        help="footage impairments (default medium)",
    )
    laser.add_argument("--size", type=_size, default=(640, 480))
    laser.add_argument("--frames", type=int, default=60)
    laser.add_argument("--fps", type=float, default=30.0)
    laser.add_argument(
        "--radius-px", type=float, help="major semi-axis / outer radius (default 30%% of height)"
    )
    laser.add_argument("--ellipticity", type=float, default=0.3, help="ellipse: 1 - minor/major")
    laser.add_argument("--loops", type=int, default=3, help="trochoid loops (2-7; hypotrochoid 3-7)")
    laser.add_argument("--b", type=float, default=0.5, help="trochoid b of Eq. 6.38")
    laser.add_argument("--rotation-deg", type=float, default=20.0)
    laser.add_argument("--cycle-hz", type=float, default=7.3, help="main-loop frequency of the spot")
    laser.add_argument("--exposure-ms", type=float, help="exposure per frame (default from --level)")
    laser.add_argument("--codec", default="mp4v", help="fourcc: mp4v (.mp4), MJPG (.avi), FFV1 (.mkv)")
    laser.add_argument("--seed", type=int, default=0)
    laser.add_argument("--brightness", type=float, help="trace peak / full scale (default from --level)")
    laser.add_argument("--background", type=float, help="grey level of the screen (default from --level)")
    laser.add_argument("--noise", type=float, help="sensor noise sigma in grey levels (default from --level)")
    laser.add_argument("--laser-bgr", type=_bgr, help="B,G,R response to the laser (default 0.25,0.3,1: red)")
    laser.add_argument("--screen-bgr", type=_bgr, help="B,G,R tint of the screen light (default 1,1,1; "
                                                       "0.7,0.88,1 is a warm lamp)")
    laser.add_argument("--angles", metavar="RUN", help="simulator run: t_s, tilt_x_rad, tilt_y_rad")
    laser.add_argument("--screen-distance-mm", type=float, default=500.0, help="with --angles")
    laser.add_argument("--mm-per-px", type=float, default=0.5, help="with --angles")
    add_json_argument(laser, "the files written and the ground truth")
    laser.set_defaults(func=run_laser)

    strobe = kinds.add_parser("strobe", help="stroboscopic side view of the floating magnet")
    strobe.add_argument("out")
    strobe.add_argument("--level", choices=["easy", "medium", "hard"], default="medium")
    strobe.add_argument("--frames", type=number(2, 100_000, integer=True), default=48)
    strobe.add_argument("--rotor-hz", type=number(0, 10_000, low_open=True), default=240.0,
                        help="rotor revolutions per second (default 240: 14 400 RPM)")
    strobe.add_argument("--strobe-hz", type=number(0, 10_000, low_open=True), default=15.15,
                        help="flashes (and frames) per second (default 15.15: 2.4 Hz apparent at 240 Hz)")
    strobe.add_argument("--tilt-rad", type=float, default=0.25, help="tilt amplitude phi")
    strobe.add_argument("--rc-offset-px", type=float, default=60.0, help="delta of Eq. 5.97")
    strobe.add_argument("--codec", default="mp4v")
    strobe.add_argument("--seed", type=int, default=0)
    add_json_argument(strobe, "the files written and the ground truth")
    strobe.set_defaults(func=run_strobe)

    testset = kinds.add_parser("testset", help="the seeded acceptance set (laser clips) into a folder")
    testset.add_argument("folder")
    add_json_argument(testset, "the files written")
    testset.set_defaults(func=run_testset)
    parser.set_defaults(func=lambda args: parser.print_help() or 1)


def load_angles(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t_s, tilt_x_rad, tilt_y_rad)`` from a CSV (optional header), .npy (N, 3) or .npz."""
    import numpy as np

    p = Path(path)
    if not p.exists():
        raise VideoError(path, "no such file")
    try:
        if p.suffix == ".npz":
            d = np.load(p)
            arr = np.column_stack([d["t_s"], d["tilt_x_rad"], d["tilt_y_rad"]])
        elif p.suffix == ".npy":
            arr = np.load(p)
        else:
            arr = np.genfromtxt(p, delimiter=",", comments="#")
            arr = arr[~np.isnan(arr).any(axis=1)] if arr.ndim == 2 else arr
    except (OSError, ValueError, KeyError) as exc:
        raise VideoError(path, f"cannot read angles: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] < 3 or len(arr) < 2:
        raise VideoError(path, "expected at least 2 rows of t_s, tilt_x_rad, tilt_y_rad")
    if not np.all(np.diff(arr[:, 0]) > 0):
        raise VideoError(path, "t_s must increase")
    return arr[:, 0], arr[:, 1], arr[:, 2]


def run_laser(args: argparse.Namespace) -> int:
    import numpy as np

    from labkit.synth import laser_truth, positions_from_angles, render_laser, write_clip
    from labkit.synth.presets import laser_pattern, laser_preset

    spec = laser_preset(args.level, args.size, args.seed)
    kw = {}
    if args.pattern == "ellipse":
        kw["ellipticity"] = args.ellipticity
    elif args.pattern != "circle":
        if not 2 <= args.loops <= 7 or (args.pattern == "hypotrochoid" and args.loops < 3):
            raise VideoError(args.out, "loops must be 2-7 for an epitrochoid and 3-7 for a hypotrochoid")
        kw.update(loops=args.loops, b=args.b)
    pattern = laser_pattern(args.pattern, args.size, rotation_deg=args.rotation_deg, **kw)
    if args.radius_px:
        f = args.radius_px / (
            pattern.semi_axes[0] if pattern.kind in ("circle", "ellipse") else pattern.scale * (1 + pattern.b)
        )
        pattern = replace(pattern, semi_axes=tuple(a * f for a in pattern.semi_axes), scale=pattern.scale * f)
    spec = replace(
        spec, pattern=pattern, frames=args.frames, fps=args.fps, cycle_hz=args.cycle_hz, codec=args.codec
    )
    if args.exposure_ms is not None:
        spec = replace(spec, exposure_s=args.exposure_ms / 1000)
    looks = {"brightness": args.brightness, "background": args.background, "noise_sigma": args.noise,
             "laser_bgr": args.laser_bgr, "background_bgr": args.screen_bgr}
    spec = replace(spec, **{k: v for k, v in looks.items() if v is not None})
    position, truth = None, None
    if args.angles:
        t, tx, ty = load_angles(args.angles)
        centre = (args.size[0] / 2, args.size[1] / 2)
        spec = replace(spec, pattern=replace(pattern, center=centre))
        position = positions_from_angles(t, tx, ty, args.screen_distance_mm, args.mm_per_px, centre)
        truth = {
            "kind": "laser",
            "spec": spec.to_dict(),
            "angles": args.angles,
            "screen_distance_mm": args.screen_distance_mm,
            "mm_per_px": args.mm_per_px,
            "tilt_rad": {"x_max": float(np.abs(tx).max()), "y_max": float(np.abs(ty).max())},
            "pattern": None,
        }
    truth = truth or laser_truth(spec)
    path = write_clip(args.out, _progress(render_laser(spec, position), args.out, spec.frames), spec.fps,
                      spec.codec, truth)
    w, h = spec.size
    print(f"wrote {path} ({spec.frames} frames {w}x{h}, {args.level}) and {_written(path, None)['truth']}")
    write_json(_written(path, truth), args.json, "synth")
    return 0


def run_strobe(args: argparse.Namespace) -> int:
    from labkit.synth import render_strobe, strobe_truth, write_clip
    from labkit.synth.presets import strobe_preset

    spec = replace(
        strobe_preset(args.level, args.seed),
        frames=args.frames,
        rotor_hz=args.rotor_hz,
        strobe_hz=args.strobe_hz,
        tilt_amplitude_rad=args.tilt_rad,
        rc_offset_px=args.rc_offset_px,
        codec=args.codec,
    )
    if not 0 < spec.tilt_amplitude_rad < math.pi / 2:
        raise VideoError(args.out, "--tilt-rad must lie in (0, pi/2)")
    problem = strobe_coverage_problem(spec.rotor_hz, spec.strobe_hz, spec.frames)
    if problem is not None and problem.startswith(STILL):
        raise VideoError(args.out, problem)  # nothing moves: no clip is worth writing
    if problem is not None:  # written (a clip to test poor coverage is a use), but said
        print(f"labkit synth: warning: {args.out}: {problem}", file=sys.stderr)
    truth = strobe_truth(spec)
    path = write_clip(args.out, _progress(render_strobe(spec), args.out, spec.frames), spec.strobe_hz,
                      spec.codec, truth)
    print(f"wrote {path} ({spec.frames} frames, apparent {abs(spec.apparent_hz):.3f} Hz) and "
          f"{_written(path, None)['truth']}")
    write_json(_written(path, truth), args.json, "synth")
    return 0


def phase_spread(apparent_hz: float, strobe_hz: float, frames: int) -> float:
    """How evenly ``frames`` flashes sample the apparent cycle: twice the smaller eigenvalue of the
    covariance of (sin psi, cos psi), 1 for uniform phases, 0 for one phase (the measure
    ``labkit analyse strobe`` reports as ``phase_spread``, labkit.vision.strobe.analyse)."""
    import numpy as np

    psi = 2 * math.pi * apparent_hz * np.arange(frames) / strobe_hz
    cov = np.cov(np.vstack([np.sin(psi), np.cos(psi)]))
    return float(2 * max(0.0, np.linalg.eigvalsh(cov)[0]))


#: how a still clip's problem starts (refused; a poorly covered cycle is only warned about)
STILL = "a still clip: "


def strobe_coverage_problem(rotor_hz: float, strobe_hz: float, frames: int) -> str | None:
    """Why a clip of these settings cannot be measured by ``labkit analyse strobe`` (None: it
    can): an apparent frequency of 0 (the rotor turns a whole number of times between flashes)
    shows a still body (the text starts with :data:`STILL`); too few frames for the apparent
    cycle sample too little of it."""
    from labkit.vision.strobe.checks import MIN_PHASE_SPREAD

    ratio = rotor_hz / strobe_hz
    apparent = (ratio - round(ratio)) * strobe_hz
    if abs(apparent) < 1e-9 * strobe_hz:
        return (f"{STILL}--rotor-hz {rotor_hz:g} is {round(ratio)} x --strobe-hz {strobe_hz:g}: the apparent "
                "frequency is 0 Hz, every flash catches the magnet at the same phase and the clip shows "
                "a still body that labkit analyse strobe cannot measure; choose a strobe a little off "
                f"rotor/n, e.g. --strobe-hz {rotor_hz / (round(ratio) + 0.16):.4g}")
    spread = phase_spread(apparent, strobe_hz, frames)
    if spread < MIN_PHASE_SPREAD:
        need = math.ceil(strobe_hz / abs(apparent))
        return (f"{frames} frames at {strobe_hz:g} Hz cover {frames * abs(apparent) / strobe_hz:.2g} of the "
                f"apparent cycle ({abs(apparent):.4g} Hz; phase spread {spread:.2f} of 1, labkit analyse "
                f"strobe needs {MIN_PHASE_SPREAD:g} and will call the clip doubtful or failed): use "
                f"--frames {need} or more, or a strobe further from rotor/n")
    return None


def run_testset(args: argparse.Namespace) -> int:
    from labkit.synth import laser_truth, render_laser, write_clip
    from labkit.synth.presets import laser_test_set

    written = []
    for name, spec in laser_test_set():
        out = Path(args.folder) / f"{name}.mp4"
        path = write_clip(out, _progress(render_laser(spec), out, spec.frames), spec.fps, spec.codec,
                          laser_truth(spec))
        written.append(_written(path, None))
        print(f"wrote {path} and {written[-1]['truth']}")
    write_json({"clips": written}, args.json, "synth")
    return 0
