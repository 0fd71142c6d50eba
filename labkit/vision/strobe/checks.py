"""The quality verdict of a stroboscope analysis (docs/reference/vision-verdicts.md, *Strobe quality
verdict*).

``strobe_quality(evidence)`` returns the ``"quality"`` object of ``labkit analyse strobe``:
``{"verdict": "ok" | "doubtful" | "failed", "reasons": [...], **evidence}``. Each rule names the
evidence it reads; the tolerances are those of the acceptance (tilt within 5 % or 0.005 rad,
lateral amplitude within 5 % or 0.5 px), so "ok" means: by the fit's own scatter and by every
check below, the numbers are within them.
"""

from __future__ import annotations

import math

from labkit.vision.shared.verdict import Verdict
from labkit.vision.strobe.body import MAX_BEND_PX

TILT_TOL_REL, TILT_TOL_ABS = 0.05, 0.005
LATERAL_TOL_REL, LATERAL_TOL_PX = 0.05, 0.5
MIN_DETECTED = 0.9  # of the frames
MIN_BODY_RADIUS_PX = 6.0  # half diagonal of the silhouette
# systematic error at the body's ends that the fit's scatter does not show, by how the axis was
# measured: the soft mask's steep edge (pixels, lens blur, compression), and the moments linear in
# intensity of a clip without a ghost (blur-invariant; analysis/strobe_subpixel_bias.py measures
# 0.07 px at most for the tilt amplitude of 60 random blurred clips, rounded up for compression)
SUBPIXEL_BIAS_PX = {"soft mask": 0.2, "linear moments": 0.1, "linear moments, room light taken out": 0.1}
MAX_BODY_FRACTION = 0.45  # half length against the frame's shorter side
MAX_AREA_SPREAD = 0.2  # relative standard deviation of the body's area
AMBIGUOUS_ANISOTROPY = (0.12, 0.35)  # between square (4-fold) and elongated (2-fold)
MIN_PHASE_SPREAD, FAILED_PHASE_SPREAD = 0.3, 0.08
MAX_RESIDUAL_RATIO = 2.5  # sinusoid residual against the phase-neighbour noise
RUNNER_UP_CLOSE = 0.9  # runner-up frequency explains this much of what the best does
MAX_FLASH_SPREAD_CYCLES = 0.125  # flashes spread over u cycles shrink amplitudes by 1 - sinc(u): 2.5 %, half
# the tolerance
LOCKED_WEAK, LOCKED_STRONG = 0.5, 0.8  # explained variance of tilt vs lateral (they move together)
MAX_ROOM_LIGHT = 0.5  # room light's share of the light (room_light): above it the ghost outweighs the body
# the room light is fitted on a few frames (room_light.FIT_FRAMES); the tilt measured on those frames
# and on every frame with the same ghosts taken out agree within this share when the fit holds
# for the clip (the robustness suite's strobe cases that pass with verdict ok: within 5 %; a fit
# that did not hold, strobe-cylinder-26-hard: 16 %, and its tilt 0.012 rad off)
ROOM_LIGHT_HOLDS = 0.10


def tilt_tolerance(phi: float) -> float:
    """The tilt amplitude's tolerance (rad): 5 % of it, at least 0.005 rad (the acceptance's)."""
    return max(TILT_TOL_REL * phi, TILT_TOL_ABS)


def lateral_tolerance(beta: float) -> float:
    """The lateral amplitude's tolerance (px): 5 % of it, at least 0.5 px (the acceptance's)."""
    return max(LATERAL_TOL_REL * beta, LATERAL_TOL_PX)


def _sinc(u: float) -> float:
    return math.sin(math.pi * u) / (math.pi * u) if u else 1.0


def _amplitude_checks(v: Verdict, e: dict) -> None:
    phi, phi_se = e["tilt_amplitude_rad"], e["tilt_amplitude_se_rad"]
    tol = tilt_tolerance(phi)
    if phi_se > 10 * tol:
        v.fail(f"no tilt above the noise: {phi:.4f} +- {phi_se:.4f} rad")
    elif (bias := SUBPIXEL_BIAS_PX[e.get("axis_method", "soft mask")]) / e["body_radius_px"] > tol:
        v.doubt(f"body small for its tilt: {e['body_radius_px']:.1f} px from centre to corner, so a "
                f"{bias} px bias at its ends (pixels, lens blur, compression) turns it by "
                f"{bias / e['body_radius_px']:.4f} rad, more than the tolerance of {tol:.4f} rad")
    elif 3 * phi_se > tol:
        v.doubt(f"tilt amplitude uncertain: {phi:.4f} +- {phi_se:.4f} rad (1 sigma) against a tolerance "
                f"of {tol:.4f} rad")
    beta, beta_se = e["lateral_amplitude_px"], e["lateral_amplitude_se_px"]
    tol = lateral_tolerance(beta)
    if 3 * beta_se > tol:
        v.doubt(f"lateral amplitude uncertain: {beta:.2f} +- {beta_se:.2f} px (1 sigma)")


def _phase_checks(v: Verdict, e: dict) -> None:
    spread = e["phase_spread"]
    if spread < FAILED_PHASE_SPREAD:
        v.fail(f"the frames sample too little of the cycle (phase spread {spread:.2f} of 1): the "
               "clip is shorter than an apparent cycle or the apparent frequency is near 0 or half "
               "the frame rate")
    elif spread < MIN_PHASE_SPREAD:
        v.doubt(f"the frames sample the cycle unevenly (phase spread {spread:.2f} of 1)")
    if e.get("model_disagrees"):
        v.doubt(f"the given frequencies predict {e['model_apparent_hz']:.4g} Hz apparent but the body moves "
                f"at {e['signal_apparent_hz']:.4g} Hz in the footage; the footage's frequency was used "
                "(check --rotor-hz/--strobe-hz, and --camera-fps if the file's frame rate is not the "
                "camera's)")
    if e["phase_source"] == "signal" and e.get("runner_up_explained") is not None:
        if e["runner_up_explained"] >= RUNNER_UP_CLOSE * e["signal_explained"]:
            v.doubt(f"apparent frequency ambiguous: {e['runner_up_apparent_hz']:.4g} Hz explains the motion "
                    f"nearly as well as {e['signal_apparent_hz']:.4g} Hz; give --rotor-hz/--strobe-hz")
    ratio = e["tilt_residual_ratio"]
    if ratio > MAX_RESIDUAL_RATIO and e["tilt_explained"] < 0.9:
        v.doubt(f"the Eq. 5.97 sinusoid leaves {e['rms_residual_tilt_rad']:.4f} rad rms, {ratio:.1f}x the "
                "tilt's frame-to-frame noise at neighbouring phases: the phase model or the waveform is off")
    tilt_fit, lateral_fit = e["tilt_explained"], e["lateral_explained"]
    for name, weak, strong in (("tilt", tilt_fit, lateral_fit), ("lateral motion", lateral_fit, tilt_fit)):
        if weak < LOCKED_WEAK and strong > LOCKED_STRONG:
            v.doubt(f"the {name} follows the apparent frequency poorly (the sinusoid explains {weak:.0%} "
                    f"of its variance, against {strong:.0%} for the other): Eq. 5.97 locks tilt and lateral "
                    "motion; a rolling shutter with the camera as strobe, or a wrong body axis, does this")
    spread_cycles = e.get("flash_spread_cycles")
    if spread_cycles is not None and spread_cycles > MAX_FLASH_SPREAD_CYCLES:
        v.doubt(f"each frame superimposes flashes up to {spread_cycles:.2f} cycles apart: the body is seen "
                f"at several phases at once, which can shrink amplitudes by up to "
                f"{1 - _sinc(spread_cycles):.1%} (give --exposure-s to know)")


def _body_checks(v: Verdict, e: dict, per_frame: bool = True) -> None:
    """``per_frame``: False when the per-row model of a rolling shutter replaced the per-frame
    poses (a smeared silhouette's area, bend, axis and apparent ghost are then what it models)."""
    seen, frames = e["frames_with_body"], e["frames"]
    if seen < MIN_DETECTED * frames:
        v.doubt(f"body found in only {seen} of {frames} frames")
    radius = e["body_radius_px"]
    if radius < MIN_BODY_RADIUS_PX:
        v.doubt(f"body small: {radius:.1f} px from its centre to a corner; tilt is poorly resolved")
    if e["body_size_fraction"] > MAX_BODY_FRACTION:
        v.doubt(f"body large against the frame ({e['body_size_fraction']:.0%} of its shorter side)")
    if e.get("truncated"):
        v.doubt(str(e["truncated"]))
    if not per_frame:
        return
    if e["body_area_spread"] > MAX_AREA_SPREAD:
        camera = e.get("phase_source") == "camera"  # no lamp: a rolling shutter smears the body
        v.doubt(f"body area varies by {e['body_area_spread']:.0%} between frames: segmentation unstable "
                "(shadow, ghost, or several images per frame" + (
                    "; or, with the camera as the strobe, a rolling shutter reading rows at different "
                    "rotor phases: if the shutter rolls, give --readout-ms for the per-row model)" if camera
                    else ")"))
    if e["body_bend_px"] > MAX_BEND_PX:
        v.doubt(f"the body's silhouette is bent (its midline strays {e['body_bend_px']:.2f} px rms from a "
                "straight line): a rolling shutter shows different rows at different rotor phases, which "
                "with the camera as the strobe distorts tilt and lateral motion")
    lo, hi = AMBIGUOUS_ANISOTROPY
    if lo < e["body_anisotropy"] < hi:
        v.doubt(f"silhouette neither square nor elongated (anisotropy {e['body_anisotropy']:.2f}): its axis "
                f"was taken {e['body_symmetry']}-fold")
    _room_light_checks(v, e)


def _room_light_checks(v: Verdict, e: dict) -> None:
    share = e.get("room_light_fraction")
    if share is None:
        return
    if not e.get("room_light_settled", True):
        v.doubt(f"the room-light correction did not settle (room light {share:.0%} of the light): the tilt "
                f"still moved between its last two rounds; uncorrected it is "
                f"{e['tilt_amplitude_uncorrected_rad']:.4f} rad; film with less ambient light")
    phi, phi0 = e["tilt_amplitude_rad"], e["tilt_amplitude_uncorrected_rad"]
    beta, beta0 = e["lateral_amplitude_px"], e["lateral_amplitude_uncorrected_px"]
    moved = []
    if abs(phi - phi0) > tilt_tolerance(phi):
        moved.append(f"tilt {phi0:.4f} -> {phi:.4f} rad")
    if abs(beta - beta0) > lateral_tolerance(beta):
        moved.append(f"lateral {beta0:.2f} -> {beta:.2f} px")
    if moved:
        v.doubt(f"room light ({share:.0%} of the light) left a ghost whose removal moved the result by more "
                f"than the tolerance ({', '.join(moved)}): the result rests on the model "
                "of that ghost (room light only; a flash shadow or other light that moves with the body "
                "is not in it); film with less ambient light")
    on_fitted, frames = e.get("tilt_amplitude_fitted_frames_rad"), e.get("room_light_frames_fitted")
    if on_fitted is not None and abs(phi - on_fitted) > ROOM_LIGHT_HOLDS * max(phi, 1e-12):
        v.doubt(f"the room-light correction, fitted on {frames} frames, does not hold for the whole clip: "
                f"the tilt is {on_fitted:.4f} rad on those frames and {phi:.4f} rad on all of them "
                f"(more than {ROOM_LIGHT_HOLDS:.0%} apart); film with less ambient light")
    if share > MAX_ROOM_LIGHT:
        v.doubt(f"room light is {share:.0%} of the light: the ghost of the revolution outweighs the body's "
                "own image in the flashes, and the correction rests on the model of that ghost; "
                "film with less ambient light")


def strobe_quality(evidence: dict) -> dict:
    """The ``quality`` object: verdict, reasons, then the evidence as given."""
    v = Verdict()
    rolling = evidence.get("rolling_shutter") is not None
    _body_checks(v, evidence, per_frame=not rolling)
    if rolling:  # the per-row model of a rolling shutter with the camera as the strobe
        from labkit.vision.strobe.rolling_analysis import rolling_checks
        rolling_checks(v, evidence)
    else:
        _phase_checks(v, evidence)
    _amplitude_checks(v, evidence)
    return {"verdict": v.verdict, "reasons": v.reasons, **evidence}

