"""``labkit analyse {laser,strobe} PATH``: measure laser-trace patterns and stroboscope footage.

Prints a short summary; ``--json OUT`` writes the full result (``-`` for stdout). Exit status 0 on
success, 1 when a usable file holds no trace (pattern "none", with the reason), 2 for unusable
input (missing, unreadable, truncated to nothing, all black or white, no body).
``--rerun SPEC`` is handed to ``labkit.stream.vision.open_vision_stream`` when that module exists.
``--speed-rpm`` (rotor speed while filming) and ``--spin-rad-s`` (floator spin) are recorded as
top-level ``rotor_speed_rpm`` and ``spin_rad_s`` (null when not given), so that ``labkit fit
*.json --model cone-angle`` can fit cone angle against speed (Eq. 5.24, Eq. 5.68 with spin).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from labkit.cli.numbers import number
from labkit.cli.output import add_json_argument, write_json
from labkit.cli.parsers import command_parser
from labkit.cli.progress import ProgressLines
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import LabkitError, VideoError

if TYPE_CHECKING:
    from labkit.vision.laser.result import LaserPattern, LaserResult
    from labkit.vision.shared.result import AnalysisResult
    from labkit.vision.strobe.result import OverlayFrame, StrobeResult

R = TypeVar("R", bound="AnalysisResult")


def _roi(text: str) -> tuple[int, int, int, int]:
    try:
        x, y, w, h = (int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError("expected x,y,w,h in pixels") from None
    return x, y, w, h


def _positive(text: str) -> float:
    v = float(text)
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return v


#: a screen closer than this to the magnet catches no reflected trace: the magnet and its
#: mirror are several millimetres across (a distance typed in metres lands below it)
MIN_SCREEN_DISTANCE_MM = 10.0
#: camera scales on a screen: 1 um to 10 mm per pixel (a scale in metres lands below)
MM_PER_PX_BOUNDS = (1e-3, 10.0)


def _screen_distance_mm(text: str) -> float:
    v = _positive(text)
    if v < MIN_SCREEN_DISTANCE_MM:
        hint = (f"; looks like metres: did you mean --screen-distance-mm {v * 1e3:g}?"
                if v * 1e3 >= MIN_SCREEN_DISTANCE_MM else "")
        raise argparse.ArgumentTypeError(
            f"{text} mm from the magnet to the screen is closer than a screen can catch the reflected "
            f"beam (at least {MIN_SCREEN_DISTANCE_MM:g} mm){hint}")
    return v


def _mm_per_px(text: str) -> float:
    v = _positive(text)
    low, high = MM_PER_PX_BOUNDS
    if not low <= v <= high:
        hint = f"; looks like metres per pixel: did you mean {v * 1e3:g}?" if low <= v * 1e3 <= high else ""
        raise argparse.ArgumentTypeError(f"{text} mm per pixel is outside the {low:g}-{high:g} mm/px of a "
                                         f"camera watching a screen{hint}")
    return v


def _nonnegative(text: str) -> float:
    v = _finite(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more, got {text}")
    return v


def _finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    return v


def _add_speed_arguments(parser: argparse.ArgumentParser, rotor_hz_note: str = "") -> None:
    parser.add_argument("--speed-rpm", type=_positive, metavar="RPM",
                        help="rotor speed while filming (tachometer), recorded as rotor_speed_rpm for "
                             "`labkit fit --model cone-angle`" + rotor_hz_note)
    parser.add_argument("--spin-rad-s", type=_finite, metavar="W",
                        help="floator spin while filming, recorded as spin_rad_s (Eq. 5.68 uses it)")


def register(sub: argparse._SubParsersAction) -> None:
    parser = command_parser(sub, "analyse", COMMAND_SUMMARIES["analyse"], __doc__)
    kinds = parser.add_subparsers(dest="kind", metavar="KIND")

    laser = kinds.add_parser("laser", help="circle/ellipse/trochoid pattern of a reflected laser beam")
    laser.add_argument("path", help="video (any container OpenCV reads) or long-exposure photo")
    laser.add_argument("--screen-distance-mm", type=_screen_distance_mm,
                       help=f"magnet-to-screen distance L in mm (at least {MIN_SCREEN_DISTANCE_MM:g})")
    laser.add_argument("--mm-per-px", type=_mm_per_px, help="screen scale S, mm on the screen per pixel")
    laser.add_argument("--stride", type=int, default=1, help="analyse every N-th frame (default 1)")
    laser.add_argument("--roi", type=_roi, help="x,y,w,h region of interest in px (default: whole frame)")
    laser.add_argument("--no-subpixel", action="store_true", help="skip sub-pixel refinement")
    laser.add_argument("--chunk-s", type=number(0, 3600, low_open=True), default=0.5,
                       help="seconds of video per accumulation chunk: time resolution of drift (default 0.5)")
    laser.add_argument("--max-chunks", type=int, default=12,  # LaserQuality.max_chunks (not imported here)
                       help="at most this many chunks; long clips get longer ones (default 12)")
    path = laser.add_mutually_exclusive_group()
    path.add_argument("--colour-frames", action="store_true",
                      help="force the brightest colour channel of BGR frames (default: chosen per clip "
                           "from the trace's contrast-to-noise in luma and in colour on the first frames)")
    path.add_argument("--luma", action="store_true",
                      help="force the codec's luma plane (fastest; for benchmarks)")
    _add_speed_arguments(laser)
    add_json_argument(laser, "the result")
    laser.add_argument("--rerun", metavar="SPEC", help="stream frames and overlays to rerun")
    laser.add_argument("--overlay", metavar="OUT.png",
                       help="draw the fitted curve and the verdict over the accumulated trace "
                            "into this image")
    laser.set_defaults(func=run_laser)

    strobe = kinds.add_parser(
        "strobe", help="tilt, lateral amplitude and RC offset from strobe video",
        description="Phase model (docs/explanation/strobe-analysis.md): --rotor-hz with --strobe-hz is a "
                    "lamp flashing at its own rate, any number of flashes per exposure, filmed at the file's "
                    "frame rate (or --camera-fps); --rotor-hz alone means no lamp, the camera's short "
                    "exposure is the strobe; --apparent-hz gives the apparent frequency; nothing: from the "
                    "footage.")
    strobe.add_argument("path", help="stroboscope video")
    strobe.add_argument("--rotor-hz", type=_positive,
                        help="rotor frequency; alone: the camera's exposure is the strobe (Fig. 6.20)")
    strobe.add_argument("--strobe-hz", type=_positive,
                        help="lamp flash rate (with --rotor-hz); independent of the camera's frame rate")
    strobe.add_argument("--apparent-hz", type=_positive, help="apparent frequency at the camera's frame rate")
    strobe.add_argument("--camera-fps", type=_positive,
                        help="the camera's real frame rate, when the file's header says otherwise "
                             "(slow-motion or re-encoded files)")
    strobe.add_argument("--exposure-s", type=_positive,
                        help="exposure time per frame: counts flashes per frame and corrects the "
                             "amplitudes for the motion within one exposure")
    strobe.add_argument("--readout-ms", type=_nonnegative,
                        help="rolling-shutter readout, first to last row (0: global shutter); with the "
                             "camera as the strobe it fixes the per-row phase model's line time, which "
                             "is otherwise estimated from the footage")
    strobe.add_argument("--gamma", type=_positive, default=2.2,
                        help="the camera's encoding exponent, linear = (grey / 255) ** GAMMA (default 2.2, "
                             "sRGB and Rec. 709 cameras; 1 for a linear machine-vision camera); used where "
                             "room light's ghost is taken out, since light adds in linear units")
    strobe.add_argument("--mm-per-px", type=_mm_per_px, help="scale for mm outputs")
    strobe.add_argument(
        "--point",
        choices=["tip", "bottom", "centroid"],
        default="tip",
        help="body point whose trajectory is classified (default tip)",
    )
    strobe.add_argument("--overlay", metavar="OUT.png",
                        help="draw the body axis, the rest axis and the tracked point over a frame")
    _add_speed_arguments(strobe, " (default: 60 x --rotor-hz)")
    add_json_argument(strobe, "the result")
    strobe.add_argument("--rerun", metavar="SPEC", help="stream frames and overlays to rerun")
    strobe.set_defaults(func=run_strobe)
    parser.set_defaults(func=lambda args: parser.print_help() or 1)


def open_stream(spec: str | None, kind: str):
    """The rerun hook: ``labkit.stream.vision.open_vision_stream(spec, kind)`` returns an object
    with ``frame(index, t_s, bgr)``, ``result(dict)`` and ``close()``; None if not available."""
    if not spec:
        return None
    try:
        from labkit.stream.vision import open_vision_stream  # provided by the streams work
    except ImportError:
        print(
            "labkit analyse: rerun streaming of vision results is not available yet; continuing without it",
            file=sys.stderr,
        )
        return None
    return open_vision_stream(spec, kind)


def record_speeds(result: R, speed_rpm: float | None, spin_rad_s: float | None) -> R:
    """The result with the top-level ``rotor_speed_rpm`` and ``spin_rad_s`` keys (None when not
    known) that ``labkit.fit.data`` reads to put a clip's cone angle against its rotor speed
    (Eq. 5.24)."""
    from labkit.vision.shared.result import RecordedSpeeds

    return replace(result, speeds=RecordedSpeeds(speed_rpm, spin_rad_s))


def _speed_line(r: AnalysisResult) -> str | None:
    s = r.speeds
    if s is None or (s.rotor_speed_rpm is None and s.spin_rad_s is None):
        return None
    parts = []
    if s.rotor_speed_rpm is not None:
        parts.append(f"rotor speed {s.rotor_speed_rpm:.6g} rpm")
    if s.spin_rad_s is not None:
        parts.append(f"floator spin {s.spin_rad_s:.6g} rad/s")
    return "  ".join(parts)


def _write_json(result: AnalysisResult, out: str | None) -> None:
    write_json(result.to_json(), out, "analyse")  # labkit.cli.output: '-' is stdout, alone


def _fmt(v, digits: int = 2) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def run_laser(args: argparse.Namespace) -> int:
    from labkit.vision.laser.analyse import LaserQuality, analyse_laser

    if args.stride < 1 or args.max_chunks < 1 or not args.chunk_s > 0:
        raise VideoError(args.path, "--stride and --max-chunks must be at least 1, --chunk-s positive")
    if (args.screen_distance_mm is None) != (args.mm_per_px is None):
        given, missing = (("--screen-distance-mm", "--mm-per-px") if args.mm_per_px is None
                          else ("--mm-per-px", "--screen-distance-mm"))
        print(f"labkit analyse laser: no tilt will be printed: {given} without {missing}; the tilt is "
              "0.5 atan(semi-axis x mm-per-px / screen distance) and needs both", file=sys.stderr)
    quality = LaserQuality(
        stride=args.stride, roi=args.roi, subpixel=not args.no_subpixel, chunk_s=args.chunk_s,
        max_chunks=args.max_chunks, luma=False if args.colour_frames else (True if args.luma else None),
    )
    stream = open_stream(args.rerun, "laser")
    traces: list = []
    try:
        try:
            result = analyse_laser(
                args.path,
                args.screen_distance_mm,
                args.mm_per_px,
                quality,
                on_frame=stream.frame if stream else None,
                on_trace=traces.append if (stream or args.overlay) else None,
                on_progress=ProgressLines(f"labkit analyse laser: {Path(args.path).name}", "frames"),
            )
        except ValueError as exc:
            raise VideoError(args.path, str(exc)) from None
        result = record_speeds(result, args.speed_rpm, args.spin_rad_s)
        if stream:
            stream.result(result.to_json())
        if traces:
            _laser_overlay(traces[0], result, args.overlay, stream)
    finally:
        if stream:
            stream.close()
    return _finish("laser", args, result, _print_laser, "no pattern")


def _finish(kind: str, args: argparse.Namespace, result: AnalysisResult, print_result, no_reason: str) -> int:
    """Write the JSON, print the result (unless the JSON goes to stdout), and turn a ``failed``
    verdict into one stderr line naming the file and the first reason, and exit status 1."""
    _write_json(result, args.json)
    if args.json != "-":
        print_result(result)
    if result.verdict == "failed":
        reasons = result.reasons
        print(f"labkit analyse {kind}: {args.path}: result failed: {reasons[0] if reasons else no_reason}",
              file=sys.stderr)
        return 1
    return 0


def _laser_overlay(trace, result: LaserResult, out: str | None, stream) -> None:
    """Draw the overlay; write it to ``out`` (if given) and log it to ``stream`` (if any)."""
    import cv2

    from labkit.vision.laser.overlay import draw_overlay

    image = draw_overlay(trace, result)
    if stream is not None and hasattr(stream, "overlay"):
        stream.overlay(image)
    if out:
        try:
            written = cv2.imwrite(out, image)
        except cv2.error:
            written = False
        if not written:
            raise VideoError(out, "cannot write the overlay image "
                                  "(use a .png or .jpg name in a writable folder)")


def _loops_in_words(p: LaserPattern) -> str:
    """What ``loops`` counts (Sec. 6.5): an epitrochoid's main loop and its small loops, a
    hypotrochoid's arms."""
    n = p.loops or 0
    return f"main loop + {n - 1} small" if p.type == "epitrochoid" else f"{n} arms"


def _print_laser(r: LaserResult) -> None:
    from labkit.vision.shared.verdict import in_words

    p = r.pattern
    rate = f"{r.fps:.3g} fps" if r.fps else "photo"
    print(f"{r.source}: {r.frames} frames, {r.size[0]}x{r.size[1]}, {rate}")
    q, e = r.quality, r.quality.evidence
    if e.get("frame_path") == "colour" and e.get("cnr_luma") is not None:
        print(f"frames: colour (the trace's contrast-to-noise is {e['cnr_luma']:.1f} in luma vs "
              f"{e['cnr_colour']:.1f} in colour on the first frames: too little kept in luma)")
    if not p.found or p.center_px is None or p.semi_axes_px is None:
        print(f"pattern: none ({p.reason})")
        print(f"quality: {in_words(q)}")
        return
    cx, cy = p.center_px
    major, minor = p.semi_axes_px
    print(
        f"pattern: {p.type}  centre ({cx:.2f}, {cy:.2f}) px  semi-axes {major:.2f} / {minor:.2f} px  "
        f"rotation {p.rotation_deg:.2f} deg  ellipticity {_fmt(p.ellipticity, 3)}  "
        f"rms residual {p.rms_residual_px:.2f} px"
    )
    if p.trochoid:
        t = p.trochoid
        print(
            f"trochoid (Eq. 6.38): loops {p.loops} ({_loops_in_words(p)}), "
            f"{p.symmetry}-fold symmetry  a {t.a:.4f}  b {t.b:.3f}  "
            f"scale {t.scale_px:.2f} px  rotation {t.rotation_deg:.2f} deg"
        )
    if r.tilt_rad:
        tilt = r.tilt_rad
        print(
            f"tilt amplitude: major {tilt.major:.5f} rad ({math.degrees(tilt.major):.3f} deg), "
            f"minor {tilt.minor:.5f} rad ({math.degrees(tilt.minor):.3f} deg)"
        )
    if e.get("truncated"):
        print(f"warning: {e['truncated']}")
    if _speed_line(r):
        print(_speed_line(r))
    print(f"quality: {in_words(q)}")


def _strobe_speed_rpm(speed_rpm: float | None, rotor_hz: float | None) -> float | None:
    """The tachometer's ``--speed-rpm``, else 60 x ``--rotor-hz``; warns when both disagree by > 1 %."""
    if rotor_hz is None:
        return speed_rpm
    if speed_rpm is None:
        return 60.0 * rotor_hz
    if abs(speed_rpm / (60.0 * rotor_hz) - 1) > 0.01:
        print(f"labkit analyse strobe: --speed-rpm {speed_rpm:g} differs from 60 x --rotor-hz = "
              f"{60.0 * rotor_hz:g} rpm by more than 1 %; recording --speed-rpm", file=sys.stderr)
    return speed_rpm


def run_strobe(args: argparse.Namespace) -> int:
    from labkit.vision.strobe.analyse import analyse_strobe

    if args.strobe_hz is not None and args.rotor_hz is None:
        raise LabkitError("labkit analyse strobe: --strobe-hz needs --rotor-hz (or give --apparent-hz)")
    speed_rpm = _strobe_speed_rpm(args.speed_rpm, args.rotor_hz)
    stream = open_stream(args.rerun, "strobe")
    progress = ProgressLines(f"labkit analyse strobe: {Path(args.path).name}", "frames")

    def on_frame(index: int, t_s: float, frame) -> None:
        progress(index + 1)
        if stream:
            stream.frame(index, t_s, frame)

    try:
        found = analyse_strobe(
            args.path, args.rotor_hz, args.strobe_hz, args.apparent_hz, args.mm_per_px, args.point,
            on_frame=on_frame, camera_fps=args.camera_fps,
            exposure_s=args.exposure_s, keep_frame=bool(args.overlay or stream),
            readout_s=None if args.readout_ms is None else args.readout_ms / 1000,
            encoding_gamma=args.gamma,
        )
        drawing = found.overlay_frame
        result = record_speeds(replace(found, overlay_frame=None), speed_rpm, args.spin_rad_s)
        if stream:
            stream.result(result.to_json())
        if drawing is not None:
            _strobe_overlay(drawing, result, args.overlay, stream)
    finally:
        if stream:
            stream.close()
    return _finish("strobe", args, result, _print_strobe, "no reason")


def _strobe_overlay(drawing: OverlayFrame, result: StrobeResult, out: str | None, stream) -> None:
    """Draw the strobe overlay; write it to ``out`` (if given) and hand it to the rerun stream
    (``stream.overlay(bgr)``, when the stream offers it)."""
    from labkit.vision.strobe.overlay import draw_strobe_overlay, write_strobe_overlay

    frame = drawing.bgr
    if out:
        write_strobe_overlay(out, frame, result, drawing)
    if stream is not None and hasattr(stream, "overlay"):
        stream.overlay(draw_strobe_overlay(frame, result, drawing))


def _pm(value, se, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}" + ("" if se is None else f" +- {se:.{digits}f}")


def _print_strobe(r: StrobeResult) -> None:
    from labkit.vision.shared.verdict import describe

    q, u, pm = r.quality, r.uncertainty, r.phase_model
    print(f"{r.source}: {r.frames} frames ({q.evidence['frames_with_body']} with a body), "
          f"phase from {r.phase_source}")
    extra = ""
    if pm.flashes_per_frame is not None and pm.kind == "lamp":
        up_to = "up to " if pm.cycles_per_exposure is None else ""  # exposure not given
        extra = f"  {up_to}{pm.flashes_per_frame:.3g} flashes per frame, harmonic m = {pm.harmonic_m}"
    print(f"apparent frequency {r.apparent_hz:.4f} Hz ({pm.cycles_per_frame:+.4f} cycles per frame at "
          f"{r.fps:.4g} fps){extra}")
    body = r.body
    print(f"body: rest axis {body.rest_axis_deg:.1f} deg from image +x, "
          f"{'square (tilt mod 90 deg)' if body.symmetry == 4 else 'elongated (tilt mod 180 deg)'}, "
          f"half length {body.half_length_px:.1f} px")
    print(f"tilt amplitude {_pm(r.tilt_amplitude_rad, u.tilt_amplitude_rad, 4)} rad "
          f"({math.degrees(r.tilt_amplitude_rad):.2f} deg)  lateral amplitude "
          f"{_pm(r.lateral_amplitude_px, u.lateral_amplitude_px, 2)} px  RC offset (Eq. 5.97) "
          f"{_pm(r.rc_offset_px, u.rc_offset_px, 2)} px {r.rc_offset_direction or ''}".rstrip())
    rolling = r.rolling_shutter
    if rolling:
        given = "given" if rolling.readout_given else "from the footage"
        print(f"rolling shutter, camera as the strobe: per-row phase model, readout "
              f"{rolling.readout_s * 1e3:.2f} ms ({given})")
    room = r.room_light
    if room:
        print(f"room light: {room.fraction_of_light:.0%} of the light, its ghost of the revolution taken "
              f"out in linear light (tilt {room.tilt_amplitude_uncorrected_rad:.4f} rad without)")
    print(f"{q.evidence['point']} trajectory: {r.point_pattern.type}")
    if _speed_line(r):
        print(_speed_line(r))
    print(describe(q))
