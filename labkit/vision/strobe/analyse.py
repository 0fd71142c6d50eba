"""Stroboscope analysis (Sec. 5.4.3, Fig. 5.19, 6.14, 6.20; docs/explanation/strobe-analysis.md,
*Stroboscope*): measure the floating body in every frame (:mod:`labkit.vision.strobe.body`), map frames to
rotor
phase (:mod:`labkit.vision.strobe.phase`), fit the tilt amplitude phi, the lateral amplitude beta
and the offset of the rotation centre from the centre of mass ``delta = beta / tan(phi)`` (Eq.
5.97) with standard errors (:mod:`labkit.vision.strobe.motion_fit`), and judge the result
(:mod:`labkit.vision.strobe.checks`).

Tilt is measured about the body's own mean orientation (mod pi, or mod pi/2 for a square
silhouette), so a rotor axis horizontal in the image or a rolled camera changes nothing; the
lateral position is taken across that rest axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from labkit.errors import VideoError
from labkit.vision.shared.frames import open_frames
from labkit.vision.strobe.body import (
    BodyPose,
    ClipOrientation,
    flatten_illumination,
    measure_body,
    measure_flat,
    orient_clip,
    static_light,
)
from labkit.vision.strobe.checks import strobe_quality
from labkit.vision.strobe.motion_fit import MotionFit, fit_motion, sine_fit
from labkit.vision.strobe.phase import (
    PhaseModel,
    apparent_cycles_per_frame,
    choose_phase_model,
    estimate_cycles_per_frame,
    explained_fraction,
    fold,
)
from labkit.vision.strobe.phase_pattern import phase_pattern
from labkit.vision.strobe.result import InMillimetres, OverlayFrame, StrobeResult
from labkit.vision.strobe.rolling_analysis import rolling_analysis, rolling_applies
from labkit.vision.strobe.room_light import (
    ENCODING_GAMMA,
    FIT_FRAMES,
    ClipLight,
    fit_ghosts,
    poses_without_ghost,
    read_clip_light,
    spread_frames,
    swing_of,
)

__all__ = ["analyse_strobe", "apparent_cycles_per_frame", "measure_body", "phase_pattern"]

MIN_FRAMES = 6
ROOM_LIGHT_ROUNDS = 4  # at most this many rounds of ghost removal and measurement
ROOM_LIGHT_SETTLED = 0.005  # the tilt amplitude has settled when a round changes it by less than this
# ghost fraction below which a clip counts as ghost-free: the measure's spread on clips without
# room light (|ghost| <= 0.008 on the 30 such clips of the robustness suite, noise and blur alone)
GHOST_FLOOR = 0.01
KEEP_GREY_BYTES = 96 * 2**20  # grey frames kept for the room light up to this (640x480: 320 frames)
# pixels this close to the part of the body covered in every frame are left out of the ghost
# measure: the blurred edge of that part darkens them in every frame (lens blur: core 1-2 px)
BLUR_FRINGE_PX = 3


def ghost_fraction(found: list[BodyPose], static: np.ndarray, dark: bool) -> float:
    """How much light stays where the body sweeps, as a fraction of the body's contrast: the static
    light (brightest of all frames for a dark body) on the swept pixels (inside some frame's blob,
    not inside all) against the same static light 8-15 px beyond every blob. 0 without a ghost
    (the noise bias of the max cancels between the two), ~ G h for an ambient fraction G of the
    exposure and a pixel covered a fraction h of the revolution."""
    h, w = static.shape
    union = np.zeros((h, w), np.uint8)
    count = np.zeros((h, w), np.uint16)
    crops = [p.measured_crop() for p in found]
    for c in crops:
        rh, rw = c.region.shape
        union[c.y0:c.y0 + rh, c.x0:c.x0 + rw] |= c.region
        count[c.y0:c.y0 + rh, c.x0:c.x0 + rw] += c.region > 0
    body = float(np.median([c.body_level for c in crops]))
    bg = float(np.median([c.bg_level for c in crops]))
    full = abs(bg - body)
    core = np.abs(static - body) < 0.5 * full
    swept = (union > 0) & ~core
    # next to the part covered in every frame, the lens blur of its edge darkens the static light
    # as a ghost would; a real ghost also darkens the swept pixels beyond that fringe, blur does not
    always = (count >= len(found)).astype(np.uint8) | core.astype(np.uint8)
    beyond = swept & ~(cv2.dilate(always, np.ones((2 * BLUR_FRINGE_PX + 1,) * 2, np.uint8)) > 0)
    far = (cv2.dilate(union, np.ones((31, 31), np.uint8))
           - cv2.dilate(union, np.ones((17, 17), np.uint8))) > 0
    if swept.sum() < 10 or far.sum() < 10 or full <= 0:
        return 0.0
    # the far ring's background side: a flash shadow darkens one side of it only
    far_level = np.percentile(static[far], 75 if dark else 25)
    sign = 1.0 if dark else -1.0
    ghost = float(sign * (far_level - np.median(static[swept])) / full)
    if beyond.sum() >= 10:
        ghost_beyond = float(sign * (far_level - np.median(static[beyond])) / full)
        if ghost_beyond <= GHOST_FLOOR:  # only the blurred edge of the still part: no ghost
            return min(ghost, ghost_beyond)
    return ghost


def _read_poses(path: str, on_frame, keep_frame: int | None = None, gamma: float = ENCODING_GAMMA):
    """Measure the body in every frame. Where room light leaves a ghost of the revolution
    (:func:`ghost_fraction` above ``GHOST_FLOOR``), the clip's linear light around the body is
    read too, for :func:`_without_room_light`; without one the axes come from the linear moments.
    Returns the source, the poses, the kept frame, the ghost fraction and the clip's light (or
    None)."""
    source = open_frames(path)
    poses: list[BodyPose | None] = []
    w, h = source.size  # a clip too big to keep is read again (frame count 0: unknown, keep till full)
    grays: list[np.ndarray] | None = [] if source.frame_count * w * h <= KEEP_GREY_BYTES else None
    lo, hi, kept = 255, 0, None
    brightest = darkest = None
    for index, frame in source.frames():
        if on_frame is not None:
            on_frame(index, index / source.fps if source.fps else 0.0, frame)
        lo, hi = min(lo, int(frame.min())), max(hi, int(frame.max()))
        gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        if grays is not None:  # kept for the room light's second look: the clip is decoded once
            grays.append(gray.copy() if gray is frame else gray)
            if len(grays) * gray.nbytes > KEEP_GREY_BYTES:
                grays = None
        flat = flatten_illumination(gray)
        pose = measure_flat(flat)
        poses.append(pose)
        if pose is not None:
            frame_light = static_light(flat)
            brightest = frame_light if brightest is None else np.maximum(brightest, frame_light)
            darkest = frame_light if darkest is None else np.minimum(darkest, frame_light)
        if keep_frame is not None and pose is not None and kept is None:
            kept = (index, frame.copy())  # the reader may reuse its buffer
    if hi < 16:
        raise VideoError(source.path, f"all frames are black (brightest grey level {hi})")
    if lo > 245:
        raise VideoError(source.path, "all frames are white (saturated); reduce exposure or gain")
    found = [p for p in poses if p is not None]
    ghost, light = 0.0, None
    if found:
        assert brightest is not None and darkest is not None  # set at every pose; found holds one
        dark = sum(p.measured_crop().dark for p in found) * 2 >= len(found)
        ghost = ghost_fraction(found, brightest if dark else darkest, dark)
        if ghost > GHOST_FLOOR:
            light = read_clip_light(path, poses, dark, source.size, gamma, grays)
        else:  # no ghost: the axis from moments linear in intensity (blur-invariant)
            poses = [None if p is None else p.with_linear_angles() for p in poses]
        for p in poses:
            if p is not None:
                p.crop = None
    return source, poses, kept, ghost, light


@dataclass
class _Measured:
    """One measurement of the clip: the poses, the frames with a body and their phases, the
    orientation about the magnet axis and the Eq. 5.97 fit."""

    poses: list[BodyPose | None]
    idx: np.ndarray
    psi: np.ndarray
    orient: ClipOrientation
    motion: MotionFit

    @property
    def found(self) -> list[BodyPose]:
        return [p for p in self.poses if p is not None]


def _measure(poses: list[BodyPose | None], model: PhaseModel) -> _Measured:
    idx = np.array([i for i, p in enumerate(poses) if p is not None])
    psi = model.phases(idx)
    orient = _magnet_axis(orient_clip([p for p in poses if p is not None]), psi)
    motion = fit_motion(psi, orient.tilt_rad, orient.lateral_px, model.blur_factor)
    return _Measured(poses, idx, psi, orient, motion)


def _without_room_light(light: ClipLight, first: _Measured, model: PhaseModel) -> tuple[_Measured, dict]:
    """Take the room light's ghost out (:mod:`labkit.vision.strobe.room_light`) with the swing of the
    previous measurement, measure again, and repeat until the tilt amplitude settles (changes by
    less than ``ROOM_LIGHT_SETTLED`` of itself) or ``ROOM_LIGHT_ROUNDS`` have run. The rounds
    measure only the frames the room light is fitted on (``FIT_FRAMES``, spread over the clip);
    the last fit's ghosts then come out of every frame, which is measured once."""
    fitted = set(spread_frames([k for k, p in enumerate(first.poses) if p is not None], FIT_FRAMES))
    now = _measure([p if k in fitted else None for k, p in enumerate(first.poses)], model)
    fit, change, rounds = None, math.inf, 0
    while rounds < ROOM_LIGHT_ROUNDS and change > ROOM_LIGHT_SETTLED:
        tilt = now.motion.tilt
        swing = swing_of(now.found, now.orient.axis, now.orient.tilt_rad, now.orient.lateral_px,
                         tilt.at(now.psi), tilt.amplitude)
        fit = fit_ghosts(light, now.poses, swing, last=fit)
        poses = poses_without_ghost(light, now.poses, fit)
        if sum(p is not None for p in poses) < min(MIN_FRAMES, len(fitted)):
            break
        before, now = now.motion.phi, _measure(poses, model)
        change = abs(now.motion.phi - before) / max(now.motion.phi, 1e-12)
        rounds += 1
    alpha = 0.0 if fit is None else fit.alpha
    on_fitted = now.motion.phi  # the tilt on the frames the room light was fitted on
    if fit is not None:
        whole = _measure(poses_without_ghost(light, first.poses, fit), model)
        if len(whole.idx) >= MIN_FRAMES:
            now = whole
    if len(now.idx) < MIN_FRAMES:
        now = first
    return now, {"method": "ghost of the revolution taken out in linear light "
                           "(docs/explanation/strobe-analysis.md, Room light)",
                 "fraction_of_light": alpha, "rounds": rounds, "settled": change <= ROOM_LIGHT_SETTLED,
                 "last_change": change if math.isfinite(change) else None, "frames_fitted": len(fitted),
                 "tilt_amplitude_uncorrected_rad": first.motion.phi,
                 "tilt_amplitude_fitted_frames_rad": on_fitted,
                 "lateral_amplitude_uncorrected_px": first.motion.beta}


def _phase_spread(psi: np.ndarray) -> float:
    """How evenly the phases cover the cycle: twice the smaller eigenvalue of the covariance of
    (sin psi, cos psi); 1 for uniform phases, 0 when they sit at one or two opposite points."""
    s, c = np.sin(psi), np.cos(psi)
    cov = np.cov(np.vstack([s, c]))
    return float(2 * max(0.0, np.linalg.eigvalsh(cov)[0]))


def _neighbour_noise(psi: np.ndarray, y: np.ndarray) -> float:
    """Noise of y from differences between frames at neighbouring phases (no waveform assumed)."""
    order = np.argsort(np.mod(psi, 2 * math.pi))
    d = np.diff(y[order])
    return float(np.sqrt(np.mean(d ** 2) / 2)) if d.size else 0.0


def _pick_phase(model: PhaseModel | None, idx: np.ndarray, series: list[np.ndarray], fps: float,
                path: str) -> tuple[PhaseModel, dict]:
    """The phase model used and the evidence of how well it explains the footage."""
    signal = estimate_cycles_per_frame(idx.astype(float), series)
    ev = {"signal_cycles_per_frame": signal.cycles_per_frame, "signal_explained": signal.explained,
          "signal_apparent_hz": signal.cycles_per_frame * fps if fps else None,
          "runner_up_explained": signal.runner_up_explained,
          "runner_up_apparent_hz": (signal.runner_up_cycles_per_frame or 0.0) * fps if fps else None,
          "model_disagrees": False}
    if model is None:
        if not fps:
            fps = 1.0
        return PhaseModel("signal", signal.cycles_per_frame, fps or None, signal.cycles_per_frame * fps,
                          equation="psi_k = 2 pi c k, c from the footage", source="signal"), ev
    given = explained_fraction(idx, model.cycles_per_frame, series)
    ev["model_explained"] = given
    ev["model_apparent_hz"] = abs(model.apparent_hz or 0.0)
    # the given model disagrees when the footage's own frequency leaves clearly less unexplained:
    # under half of the given model's residual variance (and a clear signal to begin with)
    if signal.explained > 0.5 and (1 - given) > 2 * (1 - signal.explained) + 0.02 and \
            abs(fold(model.cycles_per_frame) - signal.cycles_per_frame) > 1e-6:
        sign = -1.0 if (model.cycles_per_frame % 1.0) > 0.5 else 1.0
        cycles = sign * signal.cycles_per_frame
        model = replace(model, cycles_per_frame=cycles, apparent_hz=cycles * (model.camera_fps or fps),
                        source=model.source + "; frequency from the footage (the given one disagrees)")
        ev["model_disagrees"] = True
    return model, ev


def _flash_spread(model: PhaseModel, rotor_hz: float | None, strobe_hz: float | None) -> float | None:
    """Cycles of rotor phase between the first and last flash of one exposure (lamp model)."""
    if model.kind != "lamp" or not (rotor_hz and strobe_hz) or model.flashes_per_frame is None:
        return None
    if model.camera_fps and abs(model.camera_fps / strobe_hz - 1) < 1e-3:
        return 0.0  # one flash per frame, locked to the camera
    flashes = max(1.0, math.ceil(model.flashes_per_frame - 1e-9))
    return (flashes - 1) * abs(apparent_cycles_per_frame(rotor_hz, strobe_hz))


def analyse_strobe(path: str, rotor_hz: float | None = None, strobe_hz: float | None = None,
                   apparent_hz: float | None = None, mm_per_px: float | None = None,
                   point: str = "tip", on_frame=None, camera_fps: float | None = None,
                   exposure_s: float | None = None, keep_frame: bool = False,
                   readout_s: float | None = None, encoding_gamma: float = ENCODING_GAMMA) -> StrobeResult:
    """Analyse a stroboscope video; returns the ``labkit analyse strobe`` result (its JSON:
    ``.to_json()``).

    Phase (see :mod:`labkit.vision.strobe.phase`): ``rotor_hz`` with ``strobe_hz`` (a lamp,
    any number of flashes per frame), ``rotor_hz`` alone (the camera's exposure is the strobe),
    ``apparent_hz``, or the signal. ``camera_fps`` overrides the file's frame rate,
    ``exposure_s`` (when known) gives the blur correction. ``point``: the body point whose
    trajectory is classified, ``tip`` (top end of the body axis), ``bottom`` or ``centroid``.
    ``on_frame(index, t_s, bgr)`` is called for every frame (live streams hook in here).
    ``keep_frame``: return the first frame with a body as ``result.overlay_frame`` (index, BGR)
    for an overlay (no part of the JSON). ``readout_s``: the rolling shutter's
    readout (first to last row) when known, 0 for a global shutter; with the camera as the strobe
    and a rolling shutter the amplitudes come from the per-row model
    (:mod:`labkit.vision.strobe.rolling_analysis`), the readout estimated from the footage unless given.
    ``encoding_gamma``: the camera's encoding exponent (2.2 for sRGB-like cameras, 1 for linear
    ones), with which room light's ghost is taken out in linear light
    (:mod:`labkit.vision.strobe.room_light`).
    """
    source, poses, kept, ghost, light = _read_poses(path, on_frame, 0 if keep_frame else None, encoding_gamma)
    fps = camera_fps or source.fps or (strobe_hz or 0.0)
    try:
        model = choose_phase_model(rotor_hz, strobe_hz, apparent_hz, camera_fps, exposure_s, source.fps)
    except ValueError as exc:
        raise VideoError(source.path, str(exc)) from None
    idx = np.array([i for i, p in enumerate(poses) if p is not None])
    if len(idx) < MIN_FRAMES:
        raise VideoError(source.path, f"no body found: a contrasting body was segmented in {len(idx)} of "
                                      f"{len(poses)} frames (need {MIN_FRAMES}); check lighting and framing")
    first = orient_clip([p for p in poses if p is not None])
    model, phase_ev = _pick_phase(model, idx, [first.lateral_px, first.lateral_other_px, first.tilt_rad], fps,
                                  source.path)
    measured, room = _measure(poses, model), None
    if light is not None:
        measured, room = _without_room_light(light, measured, model)
    poses, idx, psi = measured.poses, measured.idx, measured.psi
    orient, motion = measured.orient, measured.motion
    found = measured.found
    tilt, lateral = orient.tilt_rad, orient.lateral_px
    phases = [float((2 * math.pi * model.cycles_per_frame * k + motion.phase_offset) % (2 * math.pi))
              for k in range(len(poses))]
    half = float(np.median([p.half_length_along(orient.rest_angle_rad + t)
                            for p, t in zip(found, tilt, strict=True)]))
    sign = {"tip": 1.0, "bottom": -1.0, "centroid": 0.0}[point]
    points = np.array([[p.x, p.y] for p in found]) + sign * half * _axis_at(orient, tilt)
    if len(idx) >= 8:
        point_pattern = phase_pattern(points, np.array(phases)[idx])
    else:
        point_pattern = {"type": "none", "reason": f"only {len(idx)} frames with a body"}
    direction = None if motion.towards_top is None else (
        "towards body top" if motion.towards_top else "towards body bottom")
    apparent = model.apparent_hz if model.apparent_hz is not None else model.cycles_per_frame * fps
    rolling = _per_row(source, poses, found, orient, fps, readout_s,
                       (rotor_hz, strobe_hz, apparent_hz, camera_fps, exposure_s))
    out = {"source": source.path, "frames": len(poses), "fps": fps, "apparent_hz": abs(apparent),
           "tilt_amplitude_rad": motion.phi, "lateral_amplitude_px": motion.beta,
           "rc_offset_px": motion.delta,
           "uncertainty": {"tilt_amplitude_rad": motion.phi_se, "lateral_amplitude_px": motion.beta_se,
                           "rc_offset_px": motion.delta_se,
                           "method": "1-sigma from the least-squares residuals (scatter only, see docs)"},
           "room_light": room,
           "phase_per_frame": phases,
           # what the Eq. 5.97 fit was given, frame by frame (the report's phase figure draws it)
           "per_frame": {"index": idx.tolist(), "tilt_rad": [float(v) for v in tilt],
                         "lateral_px": [float(v) for v in lateral]},
           "point_pattern": point_pattern,
           "rc_offset_direction": direction, "phase_source": model.source, "phase_model": model,
           "body": {"rest_axis_deg": (orient.rest_axis_deg - math.degrees(motion.tilt.coef[0])) % 180.0,
                    "symmetry": orient.symmetry,
                    "half_length_px": half},
           "quality": strobe_quality(_evidence(source, poses, found, orient, model, motion, phase_ev, psi,
                                               half, point, _flash_spread(model, rotor_hz, strobe_hz),
                                               ghost, room, rolling))}
    if rolling is not None:
        _use_rolling(out, rolling)
    in_mm = se_mm = None
    if mm_per_px:  # the amplitudes reported (the per-row model's when it applies), in mm
        u = out["uncertainty"]
        in_mm = InMillimetres.scaled(out["lateral_amplitude_px"], out["rc_offset_px"], mm_per_px)
        se_mm = InMillimetres.scaled(u["lateral_amplitude_px"], u["rc_offset_px"], mm_per_px)
    frame = None
    if keep_frame and kept is not None:
        k = kept[0]
        j = int(np.searchsorted(idx, k))
        frame = OverlayFrame(index=k, bgr=kept[1], centre=[found[j].x, found[j].y],
                             axis=_axis_at(orient, tilt)[j].tolist(), rest_axis=orient.axis.tolist(),
                             half_length_px=half, point=points[j].tolist(), track=points.tolist(),
                             radius_px=math.sqrt(3 * (found[j].mu20 + found[j].mu02)))
    return StrobeResult.of(out, in_mm, se_mm, frame)


def _per_row(source, poses, found, orient: ClipOrientation, fps: float, readout_s: float | None,
             given: tuple[float | None, float | None, float | None, float | None, float | None],
             ) -> dict | None:
    """The per-row model's result when the camera is the strobe and the shutter rolls, else None.
    ``given``: rotor, strobe and apparent frequencies, camera fps and exposure as the user gave
    them (the phase model is built afresh: the per-frame path may have replaced its frequency)."""
    rotor_hz, model = given[0], choose_phase_model(*given, source.fps)
    bend_px = float(np.median([p.bend_px for p in found]))
    if model is None or rotor_hz is None or not rolling_applies(model, rotor_hz, readout_s, bend_px):
        return None  # (rolling_applies is False too without a model or a rotor frequency)
    return rolling_analysis(source.path, poses, orient, model, rotor_hz, fps, source.size[1], readout_s)


def _use_rolling(out: dict, rolling: dict) -> None:
    """The per-row model's amplitudes replace the per-frame fit's (which a rolling shutter with the
    camera as the strobe distorts); ``per_frame`` keeps what each whole frame showed."""
    out["tilt_amplitude_rad"] = rolling["tilt_amplitude_rad"]
    out["lateral_amplitude_px"] = rolling["lateral_amplitude_px"]
    out["rc_offset_px"] = rolling["rc_offset_px"]
    out["uncertainty"].update({"tilt_amplitude_rad": rolling["tilt_amplitude_se_rad"],
                               "lateral_amplitude_px": rolling["lateral_amplitude_se_px"],
                               "rc_offset_px": rolling["rc_offset_se_px"],
                               "method": "1-sigma from the per-row fit's Jacobian, residuals' correlation "
                                         "area included (scatter only, see docs)"})
    top = rolling["towards_top"]
    out["rc_offset_direction"] = None if top is None else (
        "towards body top" if top else "towards body bottom")
    out["body"]["rest_axis_deg"] = rolling["magnet_axis_deg"]
    out["rolling_shutter"] = rolling


def _magnet_axis(orient: ClipOrientation, psi: np.ndarray) -> ClipOrientation:
    """The side of the silhouette across which the centroid swings at the apparent frequency
    (Eq. 5.97: the centre of mass moves across the magnet axis). A square's sides are equal
    candidates; an elongated body keeps its long axis unless the swing across the short one is
    more than twice as large and clearly above the noise (a plate seen edge-on)."""
    here, other = sine_fit(psi, orient.lateral_px), sine_fit(psi, orient.lateral_other_px)
    margin = 1.0 if orient.symmetry == 4 else 2.0
    if other.amplitude > margin * here.amplitude and other.amplitude > 3 * other.amplitude_se():
        return orient.swapped()
    return orient


def _axis_at(orient: ClipOrientation, tilt: np.ndarray) -> np.ndarray:
    """Unit vectors (N, 2) of the body axis ("top" end) in each frame: the rest axis turned by the
    tilt, clockwise on screen (image y points down)."""
    u = orient.axis
    c, s = np.cos(tilt), np.sin(tilt)
    return np.column_stack([u[0] * c - u[1] * s, u[0] * s + u[1] * c])


def _evidence(source, poses, found, orient: ClipOrientation, model: PhaseModel, motion: MotionFit,
              phase_ev: dict, psi: np.ndarray, half: float, point: str, flash_spread, ghost: float,
              room: dict | None, rolling: dict | None = None) -> dict:
    areas = np.array([p.area_px for p in found])
    noise = _neighbour_noise(psi, orient.tilt_rad)
    w, h = source.size
    per_row = {} if rolling is None else {
        "rolling_shutter": rolling, "tilt_amplitude_rad": rolling["tilt_amplitude_rad"],
        "tilt_amplitude_se_rad": rolling["tilt_amplitude_se_rad"],
        "lateral_amplitude_px": rolling["lateral_amplitude_px"],
        "lateral_amplitude_se_px": rolling["lateral_amplitude_se_px"]}
    room_model = (f"run: ghost fraction {ghost:.3f} above {GHOST_FLOOR}" if room is not None else
                  f"not run: ghost fraction {ghost:.3f} at most {GHOST_FLOOR} (no room light's ghost seen)")
    return {"frames": len(poses), "frames_with_body": len(found), "ghost_fraction": ghost,
            "room_light_model": room_model,
            "room_light_fraction": (room or {}).get("fraction_of_light"),
            "room_light_settled": (room or {}).get("settled"),
            "tilt_amplitude_uncorrected_rad": (room or {}).get("tilt_amplitude_uncorrected_rad"),
            "tilt_amplitude_fitted_frames_rad": (room or {}).get("tilt_amplitude_fitted_frames_rad"),
            "room_light_frames_fitted": (room or {}).get("frames_fitted"),
            "lateral_amplitude_uncorrected_px": (room or {}).get("lateral_amplitude_uncorrected_px"),
            "axis_method": "linear moments" if room is None else "linear moments, room light taken out",
            "body_half_length_px": half, "body_size_fraction": half / min(w, h),
            "body_area_spread": float(np.std(areas) / np.mean(areas)),
            "body_anisotropy": orient.anisotropy, "body_symmetry": orient.symmetry,
            "body_bend_px": float(np.median([p.bend_px for p in found])),
            "body_radius_px": float(np.median([math.sqrt(3 * (p.mu20 + p.mu02)) for p in found])),
            "phase_source": model.kind, "phase_spread": _phase_spread(psi),
            "tilt_amplitude_rad": motion.phi, "tilt_amplitude_se_rad": motion.phi_se,
            "lateral_amplitude_px": motion.beta, "lateral_amplitude_se_px": motion.beta_se,
            "tilt_quadrature_rad": motion.quadrature, "tilt_explained": motion.tilt.explained,
            "lateral_explained": motion.lateral.explained,
            "rms_residual_x_px": motion.lateral.rms, "rms_residual_tilt_rad": motion.tilt.rms,
            "tilt_noise_rad": noise, "tilt_residual_ratio": motion.tilt.rms / noise if noise > 0 else 1.0,
            "flash_spread_cycles": flash_spread, **phase_ev,
            "point": point, "truncated": source.truncated, **per_row}
