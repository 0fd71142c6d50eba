"""``labkit run --resume`` holds the points it carries against the session's cassettes (issue 27,
*sessions you can trust*): a point in ``events.jsonl`` edited by hand (a force x10) would
otherwise be carried into the new run's fit without a word.

Before carrying, the session is replayed from its cassettes at the level ``labkit replay``
would choose (:func:`labkit.protocols.replay.choose_level`): exact for a virtual-clock session
(every point must come out bit for bit, :func:`labkit.protocols.replay_evidence.diff_points`),
faithful for a real-clock one (within :data:`labkit.protocols.replay_compare.POINT_TOLERANCES`),
re-analysis for an older real-clock session (its readings' raw bytes parsed again). An
interrupted session's replay ends where its cassettes end; the points before that are checked.

* A point that does not follow from the cassettes refuses the resume, naming file and line.
* A point the replay could not reach (its bytes are missing from the cassettes) is not carried:
  its step is measured again, with a warning naming file and line.
* A session without cassettes, or whose cassettes cannot be read, is carried unchecked with a
  warning saying why.
* A file whose digest differs from the one run.json recorded, or a cassette whose times run
  backwards (:mod:`labkit.session.integrity`), refuses the resume.
"""

from __future__ import annotations

from typing import Any

from labkit.errors import LabkitError
from labkit.protocols.replay_compare import diff_within
from labkit.protocols.replay_evidence import Evidence, diff_points
from labkit.session import SessionRecord
from labkit.session.integrity import integrity_problems


def replayed_points(record: SessionRecord) -> tuple[str, list[dict[str, Any]]]:
    """The replay level and the points the session's cassettes give (raises LabkitError when
    the cassettes cannot be replayed at all)."""
    from labkit.protocols.reanalyse import reanalyse_session
    from labkit.protocols.replay import choose_level, replay_session

    level = choose_level(record)
    if level == "analysis":
        return level, list(reanalyse_session(record).outcome.results.get("points") or [])
    evidence = Evidence()
    replay_session(record.path, sinks=[evidence], level=level)
    return level, evidence.points


def _diff_within(level: str, replayed: list[dict[str, Any]], recorded: list[tuple[str, Any]]) -> list[str]:
    """:func:`diff_points` for a faithful or re-analysed replay: numbers within tolerance."""
    by_step = {p.get("step"): p for p in replayed}
    out = []
    for where, point in recorded:
        again = by_step.get(point.get("step")) if isinstance(point, dict) else None
        if again is None:
            continue
        diffs = diff_within(again, point, "point")
        if diffs:
            out.append(f"{where}: this point does not follow from the cassettes ({'; '.join(diffs[:3])}; "
                       f"{level} replay): edited?")
    return out


def check_points_against_cassettes(record: SessionRecord, resume: Any,
                                   carried: list[dict[str, Any]]) -> tuple[list[dict[str, Any]], list[str]]:
    """``carried`` (the points the plan check kept) without those the cassettes could not
    confirm, and a warning per such point; raises LabkitError naming each point that contradicts
    them, or a file changed since the session ended."""
    tampered = integrity_problems(record.path, record.meta)
    if tampered:
        raise LabkitError(f"--resume {resume}: refused, the session was changed after it was recorded: "
                          + "; ".join(tampered[:5]))
    kept = {id(p) for p in carried}
    recorded = [(w, p) for w, p in record.point_events() if isinstance(p, dict) and id(p) in kept]
    if not recorded:
        return carried, []
    if not (record.path / "cassettes").is_dir():
        return carried, [f"{record.path}: no cassettes: the {len(recorded)} recorded points are carried "
                         "unchecked"]
    try:
        level, replayed = replayed_points(record)
    except LabkitError as exc:
        return carried, [f"{record.path}: the recorded points are carried unchecked: the cassettes "
                         f"cannot be replayed ({exc})"]
    edited = (diff_points(replayed, recorded) if level == "exact"
              else _diff_within(level, replayed, recorded))
    if edited:
        raise LabkitError(f"--resume {resume}: refused, the session was edited after it was recorded: "
                          + "; ".join(edited) + " (labkit replay shows every difference)")
    reached = {p.get("step") for p in replayed}
    unreached = [(w, p) for w, p in recorded if p.get("step") not in reached]
    warnings = [f"{w}: point of step {p.get('step')} is not in the cassettes' bytes (the {level} replay "
                f"ended before it); not carried, step {p.get('step')} is measured again"
                for w, p in unreached]
    dropped = {id(p) for _, p in unreached}
    return [p for p in carried if id(p) not in dropped], warnings
