"""Render suite cases on demand into a cache folder and score labkit's public analysis against
their truth.

Tolerances (issue 11, as the acceptance set): centre < 1 px, or < 1 % of the pattern's outer
diameter when the camera moves (drift, wander, shake); semi-axes within 2 % (ellipses: both;
trochoids: the outer extent ``scale (1 + b)``); loop count and trochoid kind exact; a and b within
0.05; strobe tilt amplitude within 5 % or 0.005 rad, lateral amplitude within 5 % or 0.5 px. The
analysis's own verdict (``quality.verdict``: ok | doubtful | failed) is read when present.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

from labkit.footage.laser_scene import laser_truth, render_laser
from labkit.footage.output import truth_path, write_footage
from labkit.footage.strobe_scene import render_strobe, strobe_truth
from labkit.footage.suite import CaseSpec
from labkit.footage.suite_build import build_shot

RENDER_VERSION = 3  # bump when the renderer's output changes: the cache key includes it
# the stroboscope renderer's own version: 4 sends the room light's ghost through the lens (PSF)
STROBE_RENDER_VERSION = 4
CONICS = ("circle", "ellipse")


def default_cache() -> Path:
    """``$LABKIT_FOOTAGE_CACHE`` or ``~/.cache/labkit/footage-suite``."""
    env = os.environ.get("LABKIT_FOOTAGE_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "labkit" / "footage-suite"


def case_path(case: CaseSpec, cache: Path) -> Path:
    version = STROBE_RENDER_VERSION if case.family == "strobe" else RENDER_VERSION
    key = hashlib.sha1(json.dumps([version, asdict(case)], sort_keys=True).encode()).hexdigest()[:10]
    suffix = ".jpg" if case.photo else ".mp4"
    return cache / f"{case.name}-{key}{suffix}"


def render_case(case: CaseSpec, cache: Path | None = None) -> tuple[Path, dict]:
    """The case's footage and truth, rendered now unless already in the cache."""
    path = case_path(case, cache or default_cache())
    tpath = truth_path(path)
    if path.exists() and tpath.exists():
        return path, json.loads(tpath.read_text())
    shot = build_shot(case)
    if case.family == "strobe":
        truth, frames = strobe_truth(shot), render_strobe(shot)
    else:
        truth, frames = laser_truth(shot), render_laser(shot)
    truth["case"] = asdict(case)
    tmp = path.with_name("tmp-" + path.name)
    write_footage(tmp, frames, shot.camera.fps, truth, jpeg_quality=shot.camera.jpeg_quality)
    truth_path(tmp).rename(tpath)
    tmp.rename(path)
    return path, json.loads(tpath.read_text())  # as read back from the cache next time


@dataclass
class Outcome:
    """A scored case: ``passed`` within every tolerance; ``reported`` the kind labkit reported
    (``error`` when it raised); ``verdict`` labkit's own (None when it gives none);
    ``failures`` which checks failed; ``errors`` the measured errors."""

    case: CaseSpec
    passed: bool
    reported: str
    verdict: str | None
    failures: list[str] = field(default_factory=list)
    errors: dict = field(default_factory=dict)
    message: str | None = None

    def to_dict(self) -> dict:
        return {"case": asdict(self.case), "passed": self.passed, "reported": self.reported,
                "verdict": self.verdict, "failures": self.failures, "errors": _finite(self.errors),
                "message": self.message}


def _finite(value):
    """JSON-safe: infinities and NaN (a quantity the analysis did not give) become None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def _rel(got: float | None, want: float) -> float:
    if got is None or not math.isfinite(got):
        return math.inf
    return abs(got / want - 1) if want else abs(got)


def score_laser(result: dict, truth: dict) -> tuple[list[str], dict]:
    """Failed checks and errors of a ``labkit analyse laser`` result's JSON (``to_json()``, or a file
    the command wrote) against a laser truth."""
    p, t = result.get("pattern") or {}, truth["pattern"]
    fails, err = [], {}
    kind = p.get("type", "none")
    if kind == "none" or p.get("center_px") is None:
        return ["no pattern"], err
    err["centre_px"] = math.dist(p["center_px"], t["center_px"])
    size = 2 * t["semi_axes_px"][0]
    tol = max(1.0, 0.01 * size) if truth.get("camera_moves") else 1.0
    err["centre_tolerance_px"] = tol
    if err["centre_px"] > tol:
        fails.append("centre")
    if t["type"] in CONICS:
        if kind not in CONICS:
            return [*fails, "kind"], err
        err["semi_axes_rel"] = [_rel(g, w) for g, w in zip(p["semi_axes_px"], t["semi_axes_px"], strict=True)]
        if max(err["semi_axes_rel"]) > 0.02:
            fails.append("semi-axes")
        return fails, err
    if kind != t["type"]:
        return [*fails, "kind"], err
    if p.get("loops") != t["loops"]:
        fails.append("loops")
    tr = p.get("trochoid") or {}
    err["outer_rel"] = _rel(p["semi_axes_px"][0], t["semi_axes_px"][0])
    err["a"] = abs(tr.get("a", math.inf) - t["trochoid"]["a"])
    err["b"] = abs(tr.get("b", math.inf) - t["trochoid"]["b"])
    fails += [n for n, bad in (("semi-axes", err["outer_rel"] > 0.02), ("a", err["a"] > 0.05),
                               ("b", err["b"] > 0.05)) if bad]
    return fails, err


def score_strobe(result: dict, truth: dict) -> tuple[list[str], dict]:
    """Failed checks and errors of a ``labkit analyse strobe`` result's JSON (``to_json()``, or a
    file the command wrote) against a strobe truth."""
    fails, err = [], {}
    phi, beta = result.get("tilt_amplitude_rad"), result.get("lateral_amplitude_px")
    phi_t, beta_t = truth["tilt_amplitude_rad"], truth["lateral_amplitude_px"]
    err["tilt_rad"] = abs(phi - phi_t) if phi is not None else math.inf
    err["lateral_px"] = abs(beta - beta_t) if beta is not None else math.inf
    if err["tilt_rad"] > max(0.05 * phi_t, 0.005):
        fails.append("tilt")
    if err["lateral_px"] > max(0.05 * beta_t, 0.5):
        fails.append("lateral")
    return fails, err


def analysis_inputs(truth: dict) -> dict:
    """What a user passes to ``analyse_strobe``: the rotor and lamp frequencies; with no lamp (the
    camera's exposure is the strobe) the rotor frequency alone (the file gives the frame rate)."""
    inputs = dict(truth["analysis_inputs"])
    if truth.get("camera_is_strobe"):
        inputs.pop("strobe_hz", None)
    return inputs


def _call(fn, path: Path, inputs: dict):
    """Call an analysis with the inputs a user would give, keeping those it accepts."""
    accepted = inspect.signature(fn).parameters
    return fn(str(path), **{k: v for k, v in inputs.items() if k in accepted and v is not None})


def evaluate_case(case: CaseSpec, cache: Path | None = None) -> Outcome:
    """Render (or reuse) the case, run labkit's public analysis on it, score it."""
    from labkit.errors import LabkitError
    from labkit.vision.laser.analyse import analyse_laser
    from labkit.vision.strobe.analyse import analyse_strobe

    path, truth = render_case(case, cache)
    strobe = case.family == "strobe"
    try:
        if strobe:
            result = _call(analyse_strobe, path, analysis_inputs(truth))
        else:
            result = analyse_laser(str(path))
    except LabkitError as exc:
        return Outcome(case, False, "error", "failed", ["analysis refused the file"], message=str(exc))
    verdict = result.verdict
    if strobe:
        fails, err = score_strobe(result.to_json(), truth)
        reported = "strobe"
    else:
        fails, err = score_laser(result.to_json(), truth)
        p = result.pattern
        reported = p.type
        if reported in ("epitrochoid", "hypotrochoid"):
            reported = f"{reported}-{p.loops}"
    return Outcome(case, not fails, reported, verdict, fails, err)


def truth_kind(case: CaseSpec) -> str:
    if case.family in ("epitrochoid", "hypotrochoid"):
        return f"{case.family}-{case.loops}"
    return case.family
