"""``cone-sweep``: the floator's cone angle against rotor speed, filmed (Eq. 5.24, issue 25).

For each planned speed the step ramps the rotor, settles, takes a burst of ``burst_frames``
frames from the ``camera`` while the tachometer keeps reading, and analyses the laser trace of
exactly the bytes the camera sent (the frame cassette's bytes, wrapped in an AVI without
re-encoding: :mod:`labkit.devices.camera.avi`) with :func:`labkit.vision.laser.analyse.analyse_laser`.
The cone angle is the mean tilt of the pattern's semi-axes on a screen ``screen_distance_mm``
away seen at ``mm_per_px`` (Sec. 5.2.3: a semi-axis r is a tilt atan(r / L) / 2). A burst whose
verdict is ``doubtful`` or ``failed`` is taken again once; the point keeps the retake's verdict.

Its standard error (``halves``, default on) comes from the odd and the even frames analysed apart:
``|phi_odd - phi_even| / 2``, an estimate with one degree of freedom (it doubles the analysis
time); ``labkit report`` draws it as error bars.

Result rows: step, target_rpm, speed_rad_s, speed_rpm, speed_std_rpm, cone_angle_rad,
cone_angle_deg, cone_angle_stderr_rad/_deg, verdict, reasons, frames, dropped, retaken, and
model_cone_angle_rad when the camera is the emulated one (the model's angle at that speed,
stored with the frames). Fit: Eq. 5.24
(:func:`labkit.fit.models.cone_angle.fit_cone_angle`, torques over I) on the ``ok`` points.
"""

from __future__ import annotations

import math
import statistics
import tempfile
from pathlib import Path
from typing import Any

from labkit.documents import FramesTaken
from labkit.protocols.context import RunContext
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.paper_figures import CONE_SWEEP_ROW, EQ_5_24
from labkit.protocols.params import ParamError
from labkit.rig import Rig
from labkit.units import rad_s_to_rpm, rpm_to_rad_s
from labkit.vision.laser.version import LASER_ANALYSIS


def burst_fps(frames: list[Any], nominal: float | None) -> float:
    """The frame rate a burst is analysed at: the camera's nominal rate, else the frames' own
    (their trusted times; a network stream declares none)."""
    return nominal or (len(frames) - 1) / max(frames[-1].t - frames[0].t, 1e-9)


def burst_cone_angle(frames: list[Any], fps: float, size: tuple[int, int], screen_mm: float,
                     mm_per_px: float) -> dict[str, Any]:
    """Analyse a burst's laser trace: cone angle (rad, None without a trace), verdict, reasons."""
    from labkit.devices.camera.avi import write_mjpeg_avi
    from labkit.vision.laser.analyse import analyse_laser

    with tempfile.TemporaryDirectory(prefix="labkit-burst-") as work:
        video = write_mjpeg_avi(Path(work) / "burst.avi", [f.payload for f in frames], fps, size)
        result = analyse_laser(str(video), screen_distance_mm=screen_mm, mm_per_px=mm_per_px)
    tilt = result.tilt_rad
    angle = 0.5 * (tilt.major + tilt.minor) if tilt else None
    return {"cone_angle_rad": angle, "verdict": result.verdict, "reasons": result.reasons,
            "pattern": result.pattern.to_json()}


def pattern_at_angles(pattern: dict[str, Any] | None, angle_rad: float | None, screen_mm: float,
                      mm_per_px: float, samples: int = 41) -> dict[str, Any] | None:
    """The trace's semi-axes (px) for cone angles from half to twice the measured one (in deg,
    the figure's y): each semi-axis keeps its tilt's offset from the mean and turns the beam by
    twice the tilt (Sec. 5.2.3, ``r = L tan(2 tilt)``). The live view draws a fitted angle on the
    frame with it. None for a pattern that is no ellipse or circle, or without an angle."""
    if angle_rad is None or not pattern or pattern.get("type") not in ("ellipse", "circle"):
        return None
    tilts = [0.5 * math.atan(r * mm_per_px / screen_mm) for r in pattern["semi_axes_px"]]
    angles = [angle_rad * (0.5 + 1.5 * k / (samples - 1)) for k in range(samples)]
    axes = []
    for phi in angles:
        turned = [min(2.0 * (t + phi - angle_rad), 0.49 * math.pi) for t in tilts]
        axes.append([screen_mm / mm_per_px * math.tan(max(a, 0.0)) for a in turned])
    return {"y": [math.degrees(phi) for phi in angles], "semi_axes_px": axes}


class ConeSweep(ProtocolDef):
    name = "cone-sweep"
    summary = "cone angle vs rotor speed from the filmed laser trace (Eq. 5.24)"
    fit_model = "cone-angle"
    row = CONE_SWEEP_ROW
    image_analysis = LASER_ANALYSIS
    hints = EQ_5_24
    defaults: dict[str, Any] = {
        "speeds_rpm": [5000.0 + 1000.0 * i for i in range(6)],  # 5000:10000:1000
        "burst_frames": 30,
        "screen_distance_mm": 500.0,
        "mm_per_px": 2.0,
        "settle_timeout_s": 0.0,  # 0: the rig's control.settle_timeout
        "halves": True,           # also analyse odd and even frames apart: the cone angle's stderr
    }
    needs = (("rotor_motor", "motor"), ("rotor_tach", "tachometer"), ("camera", "camera"))

    def plan(self, rig: Rig, params: dict[str, Any]) -> list[Step]:
        speeds = list(params["speeds_rpm"])
        if not speeds:
            raise ParamError("cone-sweep: speeds_rpm is empty")
        if not 2 <= int(params["burst_frames"]) <= 1000:
            raise ParamError("--set burst_frames: must be in 2..1000")
        for key in ("screen_distance_mm", "mm_per_px"):
            if not params[key] > 0:
                raise ParamError(f"--set {key}: must be > 0")
        ramp = rig.limits.max_ramp_rad_s2
        return [Step(i, f"{rpm:.0f} RPM", {"rotor": rpm_to_rad_s(rpm)}, {"target_rpm": rpm},
                     est_duration_s=2 * rpm_to_rad_s(rpm) / ramp + rig.control.settle_hold_s + 3.0)
                for i, rpm in enumerate(speeds)]

    def shrunk_params(self, params: dict[str, Any], how: Any, scale: float) -> dict[str, Any]:
        """Parameters of a session whose frames ``labkit shrink`` thinned (``how.kept``) and scaled."""
        return {**params, "burst_frames": how.kept(int(params["burst_frames"])),
                "mm_per_px": float(params["mm_per_px"]) / scale}

    def _burst(self, ctx: RunContext, step: Step, take: int) -> tuple[dict[str, Any], list[Any]]:
        camera = ctx.camera("camera")
        p = ctx.params
        t_start = ctx.now()
        frames = camera.burst(int(p["burst_frames"]), step=f"{step.index}.{take}")
        ctx.log_tach_readings()
        ctx.checkpoint()
        speeds = [r.value for r in ctx.tach_readings("rotor_tach", t_start)
                  if r.t <= frames[-1].t + 0.1 and math.isfinite(r.value)]
        fps = burst_fps(frames, camera.settings.fps)
        geometry = (camera.settings.size, float(p["screen_distance_mm"]), float(p["mm_per_px"]))
        result = burst_cone_angle(frames, fps, *geometry)
        pattern = result.pop("pattern")
        ctx.emit(FramesTaken(
            t=frames[-1].t, device="camera", index=step.index, take=take, seqs=[f.seq for f in frames],
            times=[f.t for f in frames], size=list(camera.settings.size), fmt=frames[-1].fmt,
            verdict=result["verdict"], pattern=pattern,
            pattern_at_y=pattern_at_angles(pattern, result["cone_angle_rad"], *geometry[1:]),
            payloads=tuple(f.payload for f in frames)))
        result["cone_angle_stderr_rad"] = None
        if p["halves"] and result["cone_angle_rad"] is not None and len(frames) >= 8:
            halves = [burst_cone_angle(frames[k::2], fps / 2, *geometry)["cone_angle_rad"] for k in (0, 1)]
            if None not in halves:
                result["cone_angle_stderr_rad"] = abs(halves[0] - halves[1]) / 2
        return {**result, "speeds": speeds, "frames": len(frames),
                "dropped": sum(f.dropped_before for f in frames[1:])}, frames

    def run_step(self, ctx: RunContext, step: Step) -> dict[str, Any]:
        ctx.set(rotor=step.targets_rad_s["rotor"])
        ctx.settle(ctx.params["settle_timeout_s"] or None)
        shot, frames = self._burst(ctx, step, 0)
        retaken = shot["verdict"] != "ok"
        if retaken:
            shot, frames = self._burst(ctx, step, 1)
        speeds = shot.pop("speeds")
        speed = statistics.fmean(speeds) if speeds else math.nan
        angle = shot["cone_angle_rad"]
        spread = rad_s_to_rpm(statistics.stdev(speeds)) if len(speeds) > 1 else math.nan
        point = {"target_rpm": step.data["target_rpm"], "speed_rad_s": speed,
                 "speed_rpm": rad_s_to_rpm(speed), "speed_std_rpm": spread,
                 **shot, "cone_angle_deg": math.degrees(angle) if angle is not None else None,
                 "cone_angle_stderr_deg": None if shot["cone_angle_stderr_rad"] is None
                 else math.degrees(shot["cone_angle_stderr_rad"]),
                 "retaken": retaken}
        meta = frames[len(frames) // 2].meta or {}
        if "model_cone_angle_rad" in meta:  # the emulated camera (also replayed): the model's angle
            point["model_cone_angle_rad"] = meta["model_cone_angle_rad"]
        return point

    def reanalyse_step(self, run: Any, step: int, events: list[dict[str, Any]]) -> dict[str, Any] | None:
        """The analysis-only rule: the step's cone angle, verdict and stderr analysed again from
        the burst the run kept in the frame cassette (the retake when it retook one) by today's
        laser analysis, with the step's recorded speed: a real-clock camera session is checked
        from its bytes, without the camera or the recording's timing."""
        from labkit.protocols.reanalysis import point_event

        recorded = point_event(events)
        if recorded is None:
            return None
        bursts = run.bursts()
        frames = bursts.frames(step, 1 if recorded.get("retaken") else 0)
        if not frames:
            return {**recorded, "cone_angle_rad": None, "verdict": "failed",
                    "reasons": [f"no frames of step {step} in the frame cassette"]}
        params = run.params
        geometry = (bursts.size, float(params["screen_distance_mm"]), float(params["mm_per_px"]))
        fps = burst_fps(frames, bursts.fps)
        result = burst_cone_angle(frames, fps, *geometry)
        result.pop("pattern", None)
        angle = result["cone_angle_rad"]
        stderr = None
        if params.get("halves") and angle is not None and len(frames) >= 8:
            halves = [burst_cone_angle(frames[k::2], fps / 2, *geometry)["cone_angle_rad"] for k in (0, 1)]
            if None not in halves:
                stderr = abs(halves[0] - halves[1]) / 2
        return {**recorded, **result, "cone_angle_stderr_rad": stderr,
                "cone_angle_deg": math.degrees(angle) if angle is not None else None,
                "cone_angle_stderr_deg": math.degrees(stderr) if stderr is not None else None}

    def fit(self, points: list[dict[str, Any]]) -> dict[str, Any]:
        from labkit.errors import FitError
        from labkit.fit.models.cone_angle import fit_cone_angle

        usable = [pt for pt in points if pt.get("verdict") == "ok" and pt.get("cone_angle_rad")
                  and math.isfinite(pt.get("speed_rad_s") or math.nan)]
        if len(usable) < 2:
            return {"model": "cone-angle", "params": {}, "note": f"{len(usable)} ok point(s): nothing to fit"}
        try:
            res = fit_cone_angle([pt["speed_rad_s"] for pt in usable],
                                 [pt["cone_angle_rad"] for pt in usable])
        except FitError as exc:
            return {"model": "cone-angle", "params": {}, "note": str(exc)}
        predicted = res.predict([pt["speed_rad_s"] for pt in usable])
        return {"model": "cone-angle", "equation": "phi = atan(tau_C / (I omega^2 - tau_S)) (Eq. 5.24)",
                "params": {k: {"value": v.value, "stderr": v.stderr, "unit": v.unit}
                           for k, v in res.params.items()},
                "steps": [pt["step"] for pt in usable] if all("step" in pt for pt in usable) else None,
                "predicted_rad": [float(x) for x in predicted], "rms_residual_rad": res.rms_residual,
                "warnings": list(res.warnings)}
