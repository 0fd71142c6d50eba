"""``strobe-sweep``: tilt amplitude phi, lateral amplitude beta and RC offset delta of the floator
against rotor speed, filmed under the strobe locked to the rotor (Eq. 5.97, issue 26).

For each planned speed the step ramps the rotor and settles, sets the strobe
(``strobe``, device kind ``strobe``: docs/reference/devices-strobe.md) to ``offset_hz`` (and ``divider``),
waits for a status line that says the flashes are locked, takes a burst of ``burst_frames`` from
the ``camera`` and waits for the status line that closes the burst. The analysis
(:func:`labkit.vision.strobe.analyse.analyse_strobe`) gets the rotor and strobe frequencies from the
strobe's own status lines over the burst (their means: nobody types them) and reads exactly the
bytes the camera sent (the frame cassette's JPEGs in an AVI, :mod:`labkit.devices.camera.avi`).
A burst whose verdict is ``doubtful`` or ``failed`` is taken again once; the point keeps the
retake's verdict. A status line with a flag that may make the flashes wrong (not locked, noise
pulse, missed flash...) during the burst makes the burst doubtful, with the flags named; no locked
line at all fails it.

Without a camera in the rig, ``clips`` names a folder of recorded clips, one per step
(``step-<index>.<ext>``, index from 0, the first matching file), filmed under the same strobe: the
step analyses that clip with the frequencies of the status lines read while it waits
``clip_s`` seconds at the speed (the clip's own frame rate; its exposure if given as
``exposure_s``). A replay reads the same files again.

Result rows (:data:`labkit.protocols.paper_figures.STROBE_SWEEP_ROW`): the speed, the strobe's
frequencies, phi, beta and delta with their standard errors (the analysis's 1-sigma from the
least-squares residuals) and verdict, and, where the camera is the emulated one (also replayed),
the model plant's values at the burst's speed (``model_phi_rad``, ``model_beta_mm``,
``model_delta_mm``, stored with the frames). Fit: Eq. 5.24 on the ``ok`` points' phi (the
floator's tilt is the cone angle of the co-rotating state).
"""

from __future__ import annotations

import math
import statistics
import tempfile
from pathlib import Path
from typing import Any

from labkit.documents import FramesTaken
from labkit.errors import LabkitError
from labkit.protocols.context import RunContext
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.paper_figures import EQ_5_97, STROBE_SWEEP_ROW
from labkit.protocols.params import ParamError
from labkit.rig import Rig
from labkit.units import rad_s_to_rpm, rpm_to_rad_s
from labkit.vision.strobe.version import STROBE_ANALYSIS

#: the strobe's status lines during a burst: one with a flag STROBE_FLAGS marks as possibly
#: wrong makes the burst doubtful; the lock wait gives up after this many seconds
LOCK_TIMEOUT_S = 5.0
CLIP_SUFFIXES = (".avi", ".mp4", ".mkv", ".mov")


def analyse_burst(video: str, freqs: dict[str, Any], fps: float | None, exposure_s: float | None,
                  mm_per_px: float) -> dict[str, Any]:
    """One burst's Eq. 5.97 result: phi, beta, delta (with standard errors), verdict, reasons."""
    from labkit.errors import VideoError
    from labkit.vision.strobe.analyse import analyse_strobe

    try:
        r = analyse_strobe(video, rotor_hz=freqs["rotor_hz"], strobe_hz=freqs["strobe_hz"], camera_fps=fps,
                           exposure_s=exposure_s, mm_per_px=mm_per_px)
    except VideoError as exc:
        return {"phi_rad": None, "verdict": "failed", "reasons": [str(exc)]}
    u, in_mm, se_mm = r.uncertainty, r.in_mm, r.uncertainty.in_mm
    assert in_mm is not None and se_mm is not None  # mm_per_px was given
    phi, phi_se = r.tilt_amplitude_rad, u.tilt_amplitude_rad
    return {"phi_rad": phi, "phi_stderr_rad": phi_se, "phi_deg": math.degrees(phi),
            "phi_stderr_deg": math.degrees(phi_se), "beta_px": r.lateral_amplitude_px,
            "beta_mm": in_mm.lateral_amplitude_mm, "beta_stderr_mm": se_mm.lateral_amplitude_mm,
            "delta_mm": in_mm.rc_offset_mm, "delta_stderr_mm": se_mm.rc_offset_mm,
            "rc_offset_direction": r.rc_offset_direction, "analysed_apparent_hz": r.apparent_hz,
            "verdict": r.verdict, "reasons": r.reasons}


def strobe_frequencies(statuses: list[Any]) -> dict[str, Any]:
    """The rotor and strobe frequencies (Hz, means of the locked lines), the apparent frequency,
    the lines used and the flags seen; ``problem`` says why they cannot be trusted (or None)."""
    from labkit.devices.strobe.protocol import STROBE_FLAGS

    locked = [s for s in statuses if s.locked]
    flags = sorted({f for s in statuses for f in s.flags})
    out: dict[str, Any] = {"strobe_lines": len(statuses), "strobe_flags": flags, "rotor_hz": None,
                           "strobe_hz": None, "apparent_hz": None, "problem": None}
    if not locked:
        out["problem"] = (f"the strobe was not locked during the burst ({len(statuses)} status lines, "
                          f"flags {', '.join(flags) or 'none'})")
        return out
    out["rotor_hz"] = statistics.fmean(s.rotor_hz for s in locked)
    out["strobe_hz"] = statistics.fmean(s.strobe_hz for s in locked)
    out["apparent_hz"] = statistics.fmean(s.apparent_hz for s in locked)
    bad = [f for f in flags if STROBE_FLAGS.get(f, (True, ""))[0]]
    if bad:
        out["problem"] = ("strobe flags during the burst: " + "; ".join(
            f"{f} ({STROBE_FLAGS[f][1] if f in STROBE_FLAGS else 'unknown flag'})" for f in bad))
    return out


#: the ``device`` of the ``frames`` document a step writes for a recorded clip: its ``times`` are
#: the window of status lines and speeds the clip was analysed with (no frames of a camera)
CLIP_DEVICE = "clips"


def burst_lines(statuses: list[Any], first: float, last: float) -> list[Any]:
    """The status lines over a burst whose frames are at ``first`` .. ``last``: from the first line
    after the first frame (its window holds that frame) to the first line after the last one (it
    closes the window holding the last frame), or to ``last`` if none came."""
    after = [s for s in statuses if s.t > last]
    end = after[0].t if after else last
    return [s for s in statuses if first < s.t <= end]


def burst_speeds(readings: list[Any], first: float, last: float) -> list[float]:
    """The tachometer's finite speeds [rad/s] read over the burst (``first`` < t <= ``last``)."""
    return [r.value for r in readings if first < r.t <= last and math.isfinite(r.value)]


def _with_problem(result: dict[str, Any], problem: str | None) -> dict[str, Any]:
    """An ``ok`` result with a problem becomes ``doubtful``; the problem joins its reasons."""
    if problem and result["verdict"] == "ok":
        result["verdict"] = "doubtful"
    if problem:
        result["reasons"] = [*result["reasons"], problem]
    return result


def burst_shot(frames: list[Any], lines: list[Any], speeds: list[float],
               camera: tuple[float | None, Any, float | None], mm_per_px: float) -> dict[str, Any]:
    """One burst analysed (Eq. 5.97) with the frequencies of its status lines; ``camera`` is the
    camera's nominal (fps, size, exposure_s). The shot's ``speeds`` and ``model`` become the
    point's speed and model columns (:func:`step_point`)."""
    from labkit.devices.camera.avi import write_mjpeg_avi

    freqs = strobe_frequencies(lines)
    problem = freqs.pop("problem")
    shot: dict[str, Any] = {"speeds": speeds, "frames": len(frames),
                            "dropped": sum(f.dropped_before for f in frames[1:]), **freqs}
    if freqs["rotor_hz"] is None:
        return {**shot, "phi_rad": None, "verdict": "failed", "reasons": [problem]}
    nominal_fps, size, exposure_s = camera
    with tempfile.TemporaryDirectory(prefix="labkit-strobe-") as work:
        fps = _frames_fps(frames, nominal_fps)
        video = write_mjpeg_avi(Path(work) / "burst.avi", [f.payload for f in frames], fps or 30.0, size)
        result = analyse_burst(str(video), freqs, fps, exposure_s, mm_per_px)
    shot["model"] = _model_truth(frames)
    dark = sum(1 for f in frames if (f.meta or {}).get("lit") is False)
    if dark:  # the emulated camera says which frames no flash lit
        problem = "; ".join(x for x in (problem, f"{dark} of {len(frames)} frames lit by no flash "
                                        "(the emulated camera's strobe was dark)") if x)
    return {**shot, **_with_problem(result, problem)}


def clip_shot(clip: str, lines: list[Any], speeds: list[float], exposure_s: float | None,
              mm_per_px: float) -> dict[str, Any]:
    """A recorded clip analysed with the frequencies of the status lines read meanwhile (the
    clip's path in the shot's ``clip``)."""
    freqs = strobe_frequencies(lines)
    problem = freqs.pop("problem")
    shot: dict[str, Any] = {"speeds": speeds, "frames": 0, "dropped": 0, **freqs, "clip": clip}
    if freqs["rotor_hz"] is None:
        return {**shot, "phi_rad": None, "verdict": "failed", "reasons": [problem]}
    return {**shot, **_with_problem(analyse_burst(clip, freqs, None, exposure_s, mm_per_px), problem)}


def step_point(target_rpm: Any, params: dict[str, Any], shot: dict[str, Any],
               retaken: bool) -> dict[str, Any]:
    """A step's row from the shot it kept: every declared column, in the declared order (phi,
    beta, delta and the verdict lead: the report's table shows the first ones); null where this
    step has none (no clip, no model)."""
    shot = dict(shot)
    speeds = shot.pop("speeds")
    model = shot.pop("model", None)
    speed = statistics.fmean(speeds) if speeds else math.nan
    spread = rad_s_to_rpm(statistics.stdev(speeds)) if len(speeds) > 1 else math.nan
    point = {"target_rpm": target_rpm, "speed_rpm": rad_s_to_rpm(speed), "speed_rad_s": speed,
             "speed_std_rpm": spread, "offset_hz": float(params["offset_hz"]),
             "divider": int(params["divider"]),
             **shot, **(model or {}), "retaken": retaken}
    columns = [c.name for c in STROBE_SWEEP_ROW if c.name != "step"]
    if undeclared := set(point) - set(columns):
        raise LabkitError(f"strobe-sweep: row keys {sorted(undeclared)} not declared in STROBE_SWEEP_ROW")
    return {name: point.get(name) for name in columns}


def recorded_statuses(record: Any, params: dict[str, Any], notes: list[str],
                      role: str = "strobe") -> list[Any]:
    """The strobe's status lines a session kept (``readings/ROLE.jsonl``), parsed again from their
    bytes by today's parser; the flags the driver added (``reset``) as recorded. NotImplementedError
    for a session without them (recorded before labkit kept them): its points stand as recorded."""
    from labkit.devices.strobe.protocol import FLAG_NAMES, StrobeStatus, parse_status_line, strip_junk

    rows = record.readings(role)
    if not rows:
        raise NotImplementedError(f"no strobe status lines in {record.path}/readings/{role}.jsonl (a session "
                                  "recorded before labkit kept them)")
    out: list[StrobeStatus] = []
    for row in rows:
        raw = str(row.get("raw", "")).encode("latin-1")
        try:
            status = parse_status_line(strip_junk(raw.strip()), float(row["t"]), role,
                                       int(row.get("divider") or params["divider"]))
        except (ValueError, KeyError) as exc:
            notes.append(f"{role}: {raw!r} at {row.get('t')} no longer parses ({exc})")
            continue
        added = frozenset(row.get("flags") or ()) - frozenset(FLAG_NAMES.values())
        out.append(StrobeStatus(**{**status.__dict__, "flags": status.flags | added}) if added else status)
    return out


def _frames_fps(frames: list[Any], fallback: float | None) -> float | None:
    """Frame rate from the frames' device times (a thinned fixture's too), else ``fallback``."""
    times = [f.t_device for f in frames]
    if len(frames) > 1 and None not in times and times[-1] > times[0]:
        return (len(frames) - 1) / (times[-1] - times[0])
    return fallback


class StrobeSweep(ProtocolDef):
    name = "strobe-sweep"
    summary = "tilt phi, lateral amplitude beta and RC offset delta vs rotor speed under the locked strobe"
    fit_model = "cone-angle"
    row = STROBE_SWEEP_ROW
    image_analysis = STROBE_ANALYSIS
    hints = EQ_5_97
    defaults: dict[str, Any] = {
        "speeds_rpm": [4000.0 + 1000.0 * i for i in range(5)],  # 4000:8000:1000
        "offset_hz": 1.0,          # apparent frequency the flashes show
        "divider": 1,              # flash every m-th revolution
        "burst_frames": 40,
        "mm_per_px": 0.0,          # 0: the emulated camera's own scale (its URL), else required
        "settle_timeout_s": 0.0,   # 0: the rig's control.settle_timeout
        "clips": "",               # without a camera: folder of recorded clips, step-<index>.<ext>
        "clip_s": 2.0,             # without a camera: how long the status lines are read per step
        "exposure_s": 0.0,         # without a camera: the clips' exposure (0: unknown)
    }
    bounds = {"offset_hz": (0.05, 20.0), "divider": (1, 100), "burst_frames": (8, 1000),
              "mm_per_px": (0.0, 100.0), "clip_s": (0.5, 60.0), "exposure_s": (0.0, 1.0)}
    needs = (("rotor_motor", "motor"), ("rotor_tach", "tachometer"), ("strobe", "strobe"))

    def plan(self, rig: Rig, params: dict[str, Any]) -> list[Step]:
        speeds = list(params["speeds_rpm"])
        if not speeds:
            raise ParamError("strobe-sweep: speeds_rpm is empty")
        if int(params["divider"]) != params["divider"]:
            raise ParamError("--set divider: a whole number of revolutions per flash")
        if "camera" not in rig.devices:
            self._check_clips(params, len(speeds))
        elif rig.devices["camera"].kind != "camera":
            raise ParamError(f"strobe-sweep: the rig's device 'camera' is a {rig.devices['camera'].kind}")
        if not params["mm_per_px"] and not self._camera_scale(rig):
            raise ParamError("--set mm_per_px: the camera's scale (mm per pixel) is needed for beta and "
                             "delta")
        ramp = rig.limits.max_ramp_rad_s2
        return [Step(i, f"{rpm:.0f} RPM", {"rotor": rpm_to_rad_s(rpm)}, {"target_rpm": rpm},
                     est_duration_s=2 * rpm_to_rad_s(rpm) / ramp + rig.control.settle_hold_s + 5.0)
                for i, rpm in enumerate(speeds)]

    @staticmethod
    def _camera_scale(rig: Rig) -> float | None:
        """``mm_per_px`` of an emulated strobe camera's URL (None for any other camera)."""
        from urllib.parse import parse_qs, urlsplit

        dev = rig.devices.get("camera")
        if dev is None or not str(dev.port).startswith("sim://camera"):
            return None
        query = parse_qs(urlsplit(str(dev.port)).query)
        if query.get("scene", [""])[0] != "strobe":
            return None
        from labkit.emulators.camera_strobe import STROBE_DEFAULTS

        return float(query.get("mm_per_px", [STROBE_DEFAULTS["mm_per_px"]])[0])

    @staticmethod
    def _check_clips(params: dict[str, Any], n: int) -> None:
        folder = Path(str(params["clips"])) if params["clips"] else None
        if folder is None:
            raise ParamError("strobe-sweep: the rig has no camera; give --set clips=FOLDER with a recorded "
                             "clip per step (step-0.mp4, step-1.mp4, ...)")
        for i in range(n):
            if _clip_of(folder, i) is None:
                raise ParamError(f"--set clips={folder}: no clip step-{i}.* ({', '.join(CLIP_SUFFIXES)}) "
                                 "for that step")

    def shrunk_params(self, params: dict[str, Any], how: Any, scale: float) -> dict[str, Any]:
        """Parameters of a session whose frames ``labkit shrink`` thinned (``how.kept``) and scaled."""
        mm = float(params["mm_per_px"])
        if not mm and scale != 1.0:
            raise LabkitError("shrink: this session took its scale from the camera's URL; scaling its "
                              "frames needs mm_per_px given to the run (--set mm_per_px=...), or shrink "
                              "with --crop only")
        return {**params, "burst_frames": how.kept(int(params["burst_frames"])), "mm_per_px": mm / scale}

    def setup(self, ctx: RunContext) -> None:
        """The lamp on (a rig file may power the strobe up dark: ``lamp = false``)."""
        ctx.strobe("strobe").lamp(True)

    # ---- one step ----------------------------------------------------------------------
    @classmethod
    def _mm_per_px(cls, params: dict[str, Any], rig: Rig) -> float:
        """The scale the analyses use: ``mm_per_px`` if given, else the emulated camera's."""
        return float(params["mm_per_px"]) or float(cls._camera_scale(rig) or 0.0)

    def _wait_lock(self, ctx: RunContext, since: float) -> None:
        """Until a status line after ``since`` says the flashes are locked (at most LOCK_TIMEOUT_S;
        the burst's own lines then say what was wrong)."""
        strobe = ctx.strobe("strobe")
        deadline = ctx.now() + LOCK_TIMEOUT_S
        while ctx.now() < deadline:
            if any(s.locked for s in strobe.statuses_since(since)):
                return
            ctx.sleep(0.05)

    def _lines_over(self, ctx: RunContext, first: float, last: float) -> list[Any]:
        """The burst's status lines (:func:`burst_lines`), once the line closing the window that
        holds its last frame has come (at most LOCK_TIMEOUT_S)."""
        strobe = ctx.strobe("strobe")
        deadline = ctx.now() + LOCK_TIMEOUT_S
        while ctx.now() < deadline and not strobe.statuses_since(last):
            ctx.sleep(0.02)
        return burst_lines(strobe.statuses_since(first), first, last)

    def _shot(self, ctx: RunContext, step: Step, take: int) -> dict[str, Any]:
        """One burst (or the step's clip) analysed with the strobe's frequencies."""
        p = ctx.params
        if "camera" in ctx.devices:
            camera = ctx.camera("camera")
            frames = camera.burst(int(p["burst_frames"]), step=f"{step.index}.{take}")
            first, last = frames[0].t, frames[-1].t
        else:
            frames, first = [], ctx.now()
            last = first + float(p["clip_s"])
            ctx.sleep(float(p["clip_s"]))
        ctx.log_tach_readings()
        ctx.checkpoint()
        lines = self._lines_over(ctx, first, last)
        ctx.log_tach_readings()  # the line closing the burst too, before the run may end
        speeds = burst_speeds(ctx.tach_readings("rotor_tach", first), first, last)
        mm_per_px = self._mm_per_px(ctx.params, ctx.rig)
        if frames:
            settings = camera.settings
            return burst_shot(frames, lines, speeds, (settings.fps, settings.size, settings.exposure_s),
                              mm_per_px)
        clip = _clip_of(Path(str(p["clips"])), step.index)
        shot = clip_shot(str(clip), lines, speeds, float(p["exposure_s"]) or None, mm_per_px)
        # the window of status lines and speeds the clip was analysed with, kept in events.jsonl
        # so the analysis-only level can analyse the clip again with the same lines
        ctx.emit(FramesTaken(t=ctx.now(), device=CLIP_DEVICE, index=step.index, take=take,
                             times=[first, last], verdict=str(shot["verdict"])))
        return shot

    def run_step(self, ctx: RunContext, step: Step) -> dict[str, Any]:
        ctx.set(rotor=step.targets_rad_s["rotor"])
        ctx.settle(ctx.params["settle_timeout_s"] or None)
        strobe = ctx.strobe("strobe")
        t_cmd = ctx.now()
        strobe.set_offset(float(ctx.params["offset_hz"]))
        strobe.set_divider(int(ctx.params["divider"]))
        self._wait_lock(ctx, t_cmd)
        shot = self._shot(ctx, step, 0)
        retaken = shot["verdict"] != "ok"
        if retaken:
            shot = self._shot(ctx, step, 1)
        return step_point(step.data["target_rpm"], ctx.params, shot, retaken)

    def reanalyse_step(self, run: Any, step: int, events: list[dict[str, Any]]) -> dict[str, Any] | None:
        """The analysis-only rule: the step's bursts analysed again from the frame cassette with
        the strobe's status lines re-parsed from ``readings/strobe.jsonl`` and the tachometer's
        readings, by the run's own rules (:func:`burst_lines`, :func:`burst_speeds`,
        :func:`burst_shot`, :func:`step_point`): phi, beta, delta, their verdict and whether the
        first burst had to be taken again all follow from the bytes."""
        from labkit.protocols.reanalysis import point_event

        recorded = point_event(events)
        if recorded is None:
            return None
        statuses = recorded_statuses(run.record, run.params, run.notes)
        speeds_of = run.readings.get("rotor_tach", [])
        if recorded.get("clip") is not None or "camera" not in run.rig.devices:
            return self._reanalyse_clip(run, step, events, recorded, statuses, speeds_of)
        bursts = run.bursts()
        camera = (bursts.fps, bursts.size, bursts.exposure_s)
        mm_per_px = self._mm_per_px(run.params, run.rig)
        shot: dict[str, Any] | None = None
        for take in (0, 1):
            frames = bursts.frames(step, take)
            if not frames:  # the burst the rule asks for is not in the cassette: said in the row
                missing = f"no frames of step {step}, take {take} in the frame cassette"
                shot = {"frames": 0, "speeds": [], "phi_rad": None, "verdict": "failed", "reasons": []} \
                    if shot is None else dict(shot)
                shot["reasons"] = [*shot["reasons"], missing]
                break
            first, last = frames[0].t, frames[-1].t
            shot = burst_shot(frames, burst_lines(statuses, first, last),
                              burst_speeds(speeds_of, first, last), camera, mm_per_px)
            if shot["verdict"] == "ok":
                break
        retaken = take == 1
        return {"step": step, **step_point(recorded.get("target_rpm"), run.params, shot or {}, retaken)}

    def _reanalyse_clip(self, run: Any, step: int, events: list[dict[str, Any]], recorded: dict[str, Any],
                        statuses: list[Any], speeds_of: list[Any]) -> dict[str, Any]:
        """A step that analysed a recorded clip: the clip analysed again with the status lines and
        speeds of the window the run recorded (its ``frames`` documents of device
        :data:`CLIP_DEVICE`), the retake too; a session recorded before those windows were kept
        cannot be re-analysed and says so."""
        windows = {int(e.get("take", 0)): e["times"] for e in events if e.get("type") == "frames"
                   and e.get("device") == CLIP_DEVICE and len(e.get("times", [])) == 2}
        clip = recorded.get("clip")
        if not windows or clip is None:
            raise NotImplementedError(f"step {step} analysed a recorded clip ({clip}) over a window of the "
                                      "strobe's status lines this session does not record (recorded before "
                                      "labkit kept it)")
        if not Path(str(clip)).is_file():
            raise NotImplementedError(f"step {step}'s clip {clip} is not there (a clip path is relative to "
                                      "the folder the run started in)")
        mm_per_px = self._mm_per_px(run.params, run.rig)
        exposure = float(run.params["exposure_s"]) or None
        shot: dict[str, Any] = {}
        for take in sorted(windows):
            first, last = (float(x) for x in windows[take])
            shot = clip_shot(str(clip), burst_lines(statuses, first, last),
                             burst_speeds(speeds_of, first, last), exposure, mm_per_px)
            if shot["verdict"] == "ok":
                break
        return {"step": step, **step_point(recorded.get("target_rpm"), run.params, shot, take == 1)}

    def fit(self, points: list[dict[str, Any]]) -> dict[str, Any]:
        from labkit.errors import FitError
        from labkit.fit.models.cone_angle import fit_cone_angle

        usable = [pt for pt in points if pt.get("verdict") == "ok" and pt.get("phi_rad")
                  and math.isfinite(pt.get("speed_rad_s") or math.nan)]
        deltas = [pt["delta_mm"] for pt in usable if pt.get("delta_mm") is not None]
        out: dict[str, Any] = {"model": "cone-angle", "params": {},
                               "delta_mean_mm": statistics.fmean(deltas) if deltas else None,
                               "delta_sd_mm": statistics.stdev(deltas) if len(deltas) > 1 else None}
        if len(usable) < 2:
            return {**out, "note": f"{len(usable)} ok point(s): nothing to fit"}
        try:
            res = fit_cone_angle([pt["speed_rad_s"] for pt in usable], [pt["phi_rad"] for pt in usable])
        except FitError as exc:
            return {**out, "note": str(exc)}
        import numpy as np  # here: `labkit --help` builds its parser without numpy

        predicted = res.predict(np.array([pt["speed_rad_s"] for pt in usable]))
        return {**out, "equation": "phi = atan(tau_C / (I omega^2 - tau_S)) (Eq. 5.24, on the tilt)",
                "params": {k: {"value": v.value, "stderr": v.stderr, "unit": v.unit}
                           for k, v in res.params.items()},
                "steps": [pt["step"] for pt in usable] if all("step" in pt for pt in usable) else None,
                "predicted_rad": [float(x) for x in predicted], "rms_residual_rad": res.rms_residual,
                "warnings": list(res.warnings)}


def _model_truth(frames: list[Any]) -> dict[str, Any] | None:
    """The emulated camera's model values over the burst (means of the frames' ``meta``), else None."""
    metas = [f.meta for f in frames if f.meta and "model_phi_rad" in f.meta]
    if not metas:
        return None
    return {key: statistics.fmean(m[key] for m in metas)
            for key in ("model_phi_rad", "model_beta_mm", "model_delta_mm")}


def _clip_of(folder: Path, index: int) -> Path | None:
    for suffix in CLIP_SUFFIXES:
        path = folder / f"step-{index}{suffix}"
        if path.is_file():
            return path
    return None
