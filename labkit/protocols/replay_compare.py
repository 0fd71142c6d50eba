"""How a faithful replay is judged (docs/explanation/replay.md, docs/decisions/0019-faithful-replay.md).

A session recorded on the real clock replays through the same protocol, control and driver
code, but its keep-alives and polls are not the recorded ones one for one, so its results are
compared within stated tolerances and its *decisions* (steps, settles, drops, interlocks and
the step of each) must be the same:

* :data:`POINT_TOLERANCES`: per result key, relative or absolute; speeds and forces within
  0.5 %; a cone angle within :data:`REPLAY_FIT_RTOL` (its burst's frames are served as
  recorded, so it is the same analysis of the same bytes).
* :func:`decisions`: the decision log of a run from its events; :func:`diff_decisions`
  compares two logs (kinds, steps, causes and reasons exactly, settle times within
  :data:`SETTLE_TOL_S`).
* :func:`offline_wording`: an offline replay moves no motor, so the words that tell a person
  at a rig what to do are taken out of what it prints.

An exact replay (virtual clock) is compared by :func:`diff_results`: everything exactly but a
fit's numbers (:data:`REPLAY_FIT_RTOL`). Every level returns a :class:`ReplayOutcome`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from labkit.protocols.analysis_versions import CrossVersion
    from labkit.protocols.runner import RunOutcome

#: Derived numbers may differ between CPUs in their last digits: BLAS and LAPACK pick different
#: kernels per instruction set, a fit sums in a different order, OpenCV's SIMD paths round
#: differently. Recorded bytes, readings and points are compared exactly; values under a derived
#: key (``fit``, and a protocol's image-analysis columns) are equal when
#: ``|a - b| <= REPLAY_FIT_RTOL * max(|a|, |b|) + REPLAY_FIT_ATOL`` (docs/explanation/replay.md).
REPLAY_FIT_RTOL = 1e-6
REPLAY_FIT_ATOL = 1e-12
DERIVED_KEYS = frozenset({"fit"})


def close_enough(a: float, b: float) -> bool:
    """Equal within :data:`REPLAY_FIT_RTOL` (and :data:`REPLAY_FIT_ATOL`); two NaNs are equal."""
    if math.isnan(a) and math.isnan(b):
        return True
    return abs(a - b) <= REPLAY_FIT_RTOL * max(abs(a), abs(b)) + REPLAY_FIT_ATOL


#: key -> ("rel" | "abs" | "count", tolerance); "count": relative, but one more or fewer always
#: passes; keys not listed compare within DEFAULT_RTOL
POINT_TOLERANCES: dict[str, tuple[str, float]] = {
    "settle_time_s": ("abs", 0.25),      # five control periods of the shipped rigs
    "hold_s": ("abs", 0.25),
    "n": ("count", 0.15),                # balance readings in the averaging window
    "unstable": ("count", 0.25),
    "strobe_lines": ("count", 0.15),     # strobe status lines over a burst: one at a window's edge
    "k": ("abs", 0.01),                  # v/w - 1: a difference of two 0.5 % numbers
    "drift_n": ("abs", 1e-4),            # N (0.01 g): rest readings of the balance
    "drift_g": ("abs", 0.01),            # the same in grams (a 0.006 g drift moved 0.5 % in a replay)
    **{key: ("rel", REPLAY_FIT_RTOL) for key in (  # a burst's own frames analysed again: they are the
        "cone_angle_rad", "cone_angle_deg",      # recorded bytes (labkit.devices.camera.faithful),
        "cone_angle_stderr_rad", "cone_angle_stderr_deg",  # so only CPU rounding may differ, as at
        "model_cone_angle_rad")},                # the exact level; the model's angle is the frames' meta
}
#: keys a newer labkit adds to a point (docs/decisions/0018-heartbeat-and-drift.md; the trial
#: spreads of a spin-critical step since issue 27): a recording
#: made before them lacks them, which is not a difference; every key it has is still compared
ADDED_KEYS = frozenset({"drift_g", "warnings", "rotor_std_rad_s", "spin_std_rad_s"})
#: every other number of a point: speeds, forces, spins
DEFAULT_RTOL = 0.005
#: spread statistics of a window and the fit's standard errors: within a factor of 3 (a reading
#: more or less at a window's edge, or a point moved by 0.5 %, changes the residuals they come
#: from by their own size)
SPREAD_RTOL = 2 / 3
#: the quick fit's parameters (from points within 0.5 %) and their uncertainties
FIT_RTOL = 0.02
FIT_STDERR_RTOL = 2 / 3
SETTLE_TOL_S = 0.25

_MOTOR_WORDS = (
    (re.compile(r"; cut the motor's power"), ""),
    (re.compile(r";? ?motors? (commanded to|at) zero"), ""),
    (re.compile(r"could not stop (\w+)"), r"the replayed stop of \1 did not match the recording"),
)


def offline_wording(text: str | None) -> str:
    """``text`` without instructions meant for a person at a running motor (an offline
    replay drives no motor; its motor commands are compared with the recording)."""
    if not text:
        return text or ""
    for pattern, replacement in _MOTOR_WORDS:
        text = pattern.sub(replacement, text)
    return text.strip()


def _tolerance(key: str, derived: bool) -> tuple[str, float]:
    if key in POINT_TOLERANCES:
        return POINT_TOLERANCES[key]
    if derived:
        return ("rel", FIT_STDERR_RTOL if key == "stderr" else FIT_RTOL)
    if "stderr" in key or "_std_" in key or key.endswith("_std"):
        return ("rel", SPREAD_RTOL)
    return ("rel", DEFAULT_RTOL)


def _within(a: float, b: float, how: tuple[str, float]) -> bool:
    if math.isnan(a) and math.isnan(b):
        return True
    kind, tol = how
    if kind == "abs":
        return abs(a - b) <= tol
    if kind == "count":
        return abs(a - b) <= max(tol * max(abs(a), abs(b)), 1.0)
    return abs(a - b) <= tol * max(abs(a), abs(b)) + 1e-12


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def diff_within(a: Any, b: Any, path: str = "results", key: str = "", derived: bool = False,
                cross: CrossVersion | None = None) -> list[str]:
    """Differences between a replay's results ``a`` and the recording's ``b`` beyond the
    faithful tolerances, each line naming the value, both numbers and the tolerance; with
    ``cross`` (a session made by another version of the image analysis) its row keys within the
    analysis's stated accuracy."""
    if _number(a) and _number(b):
        how = _tolerance(key, derived)
        if _within(float(a), float(b), how):
            return []
        unit = " s" if how[0] == "abs" and key.endswith("_s") else ""
        tol = f"{how[1] * 100:.3g} %" if how[0] != "abs" else f"{how[1]:g}{unit}"
        return [f"{path}: replay {a!r}, recording {b!r} (beyond {tol})"]
    if type(a) is not type(b):
        return [f"{path}: replay {a!r}, recording {b!r}"]
    if isinstance(a, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            if k not in b and k in ADDED_KEYS:
                continue  # a key this labkit adds, absent from an older recording
            if k not in a or k not in b:
                out.append(f"{path}.{k}: only in the {'replay' if k in a else 'recording'}")
            elif cross is not None and k in cross.accuracy:
                out += cross_diff(cross, k, a, b, f"{path}.{k}")
            else:
                out += diff_within(a[k], b[k], f"{path}.{k}", k, derived or k == "fit", cross)
        return out
    if isinstance(a, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} entries in the replay, {len(b)} in the recording"]
        return [d for i, (x, y) in enumerate(zip(a, b, strict=True))
                for d in diff_within(x, y, f"{path}[{i}]", key, derived, cross)]
    if a == b:
        return []
    return [f"{path}: replay {a!r}, recording {b!r}"]


def cross_diff(cross: CrossVersion, key: str, a: dict[str, Any], b: dict[str, Any], path: str) -> list[str]:
    """``key`` of the replay's point ``a`` against the recording's ``b`` within the stated accuracy
    of an image analysis whose version differs from the recording's."""
    if cross.agrees(key, a[key], b[key], a, b):
        return []
    return [f"{path}: replay {a[key]!r}, recording {b[key]!r} (beyond {cross.words(key)})"]


def _reason_key(reason: Any) -> str:
    """An interlock or fault reason without its numbers (a silence of 0.52 s or 0.55 s is the
    same decision), the last bytes it quotes and motor instructions."""
    text = offline_wording(str(reason or ""))
    text = re.sub(r"last bytes (\.\.\.)?b(['\"]).*?\2(?=\)|$)", "last bytes", text)  # diagnostics
    return re.sub(r"[-+]?\d[\d.,e+-]*", "#", text).strip()


def decisions(events: list[Any]) -> list[dict[str, Any]]:
    """The run's decisions from its events: each step begun, settled (with its time), each drop
    (trial, cause), each interlock and fault (reason) with the step it happened in, and how
    the run ended."""
    out: list[dict[str, Any]] = []
    step: int | None = None
    for event in events:
        e = event if isinstance(event, dict) else event.to_json()
        kind = e.get("type")
        if kind == "step":
            step = e.get("index")
            out.append({"decision": "step", "step": step, "label": e.get("label")})
        elif kind == "settled":
            out.append({"decision": "settled", "step": step, "settle_time_s": e.get("settle_time_s")})
        elif kind == "drop":
            out.append({"decision": "drop", "step": step, "trial": e.get("trial"), "cause": e.get("cause")})
        elif kind in ("interlock", "fault"):
            out.append({"decision": kind, "step": step, "reason": offline_wording(str(e.get("reason") or "")),
                        "key": _reason_key(e.get("reason"))})
        elif kind == "stop":
            out.append({"decision": "end", "step": step, "status": e.get("status")})
    return out


def describe(d: dict[str, Any], labels: dict[int, str]) -> str:
    step = d.get("step")
    where = "before the first step" if step is None else f"step {step + 1} ({labels.get(step, '?')})"
    extra = {"settled": lambda: f"settled after {d['settle_time_s']:.2f} s",
             "drop": lambda: f"drop in trial {d['trial'] + 1} seen by {d['cause']}",
             "interlock": lambda: f"interlock: {d['reason']}",
             "fault": lambda: f"stopped: {d['reason']}",
             "end": lambda: f"run ended {d['status']}",
             "step": lambda: "step began"}[d["decision"]]()
    return f"{where}: {extra}"


def diff_decisions(replayed: list[dict[str, Any]], recorded: list[dict[str, Any]]) -> list[str]:
    """Where the replay's decisions part from the recording's: the first divergence in words
    (the step, what the recording did, what the replay did), then settle times beyond
    :data:`SETTLE_TOL_S`."""
    labels = {d["step"]: d.get("label") or "" for d in recorded + replayed if d["decision"] == "step"}
    out: list[str] = []
    for i, (a, b) in enumerate(zip(replayed, recorded, strict=False)):
        loose = ("settle_time_s", "reason")  # settle times within tolerance; reasons by key
        same = ({k: v for k, v in a.items() if k not in loose}
                == {k: v for k, v in b.items() if k not in loose})
        if not same:
            out.append(f"the replay diverged at decision {i + 1}: the recording, {describe(b, labels)}; "
                       f"the replay, {describe(a, labels)}")
            return out
        if a["decision"] == "settled" and not _within(float(a["settle_time_s"]), float(b["settle_time_s"]),
                                                      ("abs", SETTLE_TOL_S)):
            out.append(f"step {a['step'] + 1}: settled after {a['settle_time_s']:.3f} s in the replay, "
                       f"{b['settle_time_s']:.3f} s in the recording (beyond {SETTLE_TOL_S:g} s)")
    if len(replayed) != len(recorded):
        longer, who = (recorded, "recording") if len(recorded) > len(replayed) else (replayed, "replay")
        extra = longer[min(len(replayed), len(recorded))]
        out.append(f"only the {who} went on: {describe(extra, labels)}")
    return out


def diff_results(a: Any, b: Any, path: str = "results", derived: bool = False,
                 derived_keys: frozenset[str] = DERIVED_KEYS, cross: CrossVersion | None = None) -> list[str]:
    """Human-readable differences between two JSON values, both values printed.

    Everything is compared exactly except numbers below a key in ``derived_keys`` (by default
    :data:`DERIVED_KEYS`; a replay adds the protocol's image-analysis columns, ``Column.analysis``),
    which are compared within :data:`REPLAY_FIT_RTOL` (their last digits depend on the CPU), and,
    with ``cross`` (a session made by another version of the image analysis), its row keys within
    the analysis's stated accuracy.
    """
    if derived and isinstance(a, int | float) and isinstance(b, int | float) \
            and not isinstance(a, bool) and not isinstance(b, bool):
        if close_enough(float(a), float(b)):
            return []
        return [f"{path}: replay {a!r} != recording {b!r} (beyond relative tolerance {REPLAY_FIT_RTOL:g})"]
    if type(a) is not type(b):
        return [f"{path}: replay {a!r} != recording {b!r}"]
    if isinstance(a, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            if k not in b and k in ADDED_KEYS:
                continue
            if k not in a or k not in b:
                out.append(f"{path}.{k}: only in {'replay' if k in a else 'recording'}")
            elif cross is not None and k in cross.accuracy:
                out += cross_diff(cross, k, a, b, f"{path}.{k}")
            else:
                out += diff_results(a[k], b[k], f"{path}.{k}", derived or k in derived_keys, derived_keys,
                                    cross)
        return out
    if isinstance(a, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} entries != {len(b)}"]
        pairs = enumerate(zip(a, b, strict=True))
        return [d for i, (x, y) in pairs
                for d in diff_results(x, y, f"{path}[{i}]", derived, derived_keys, cross)]
    if a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b)):
        return []
    return [f"{path}: replay {a!r} != recording {b!r}"]


@dataclass
class ReplayOutcome:
    outcome: RunOutcome
    recorded: dict[str, Any] | None
    identical: bool
    differences: list[str]
    #: ``file:line: reason`` of damaged lines skipped while reading the session
    warnings: list[str] = field(default_factory=list)
    level: str = "exact"
    #: faithful: per port, what its writes matched (labkit.io.faithful_port.FaithfulSerial.report)
    ports: list[dict[str, Any]] = field(default_factory=list)
    #: the replay's decisions (faithful), for reports
    decisions: list[dict[str, Any]] = field(default_factory=list)
    #: faithful: recorded timing repeated (labkit.io.replay_clock.ReplayClock.repeated)
    timing: dict[str, int] = field(default_factory=dict)
    #: analysis level: the points were recomputed from the bytes (False: a protocol without an
    #: analysis-only rule, whose points were taken as recorded)
    recomputed: bool = True
    #: the session was made by another version of its image analysis: how its numbers were
    #: compared (labkit.protocols.analysis_versions.CrossVersion.note); None for the same version
    analysis_note: str | None = None
