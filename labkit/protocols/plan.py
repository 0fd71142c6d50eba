"""A protocol's plan against a rig: refused before anything starts when the rig cannot do it
(:func:`check_plan`), printed as the dry-run table (:func:`format_plan`)."""

from __future__ import annotations

from labkit.control.loop import unreachable_target
from labkit.errors import LabkitError, SafetyError
from labkit.protocols.definition import ProtocolDef, Step
from labkit.rig import Rig
from labkit.units import rad_s_to_rpm


def check_plan(protocol: ProtocolDef, rig: Rig, steps: list[Step]) -> None:
    """Refuse a plan the rig cannot do: missing devices or loops, targets beyond the limit."""
    for role, kind in protocol.needs:
        rig.require(role, kind, needed_by=protocol.name)
    loops = {lc.name for lc in rig.control.loops}
    limit = rig.limits.max_speed_rad_s
    for step in steps:
        for loop, target in step.targets_rad_s.items():
            if loop not in loops:
                raise LabkitError(f"{protocol.name}: the rig has no speed loop {loop!r} "
                                  f"(pair a {loop}_motor with a {loop}_tach in {rig.path})")
            if target > limit:
                raise SafetyError(
                    f"{protocol.name}: step {step.index + 1} asks {rad_s_to_rpm(target):.0f} RPM, above "
                    f"the rig's limit of {rad_s_to_rpm(limit):.0f} RPM ({rig.path}: limits.max_speed); "
                    "nothing was started")
            if target < 0:
                raise SafetyError(f"{protocol.name}: step {step.index + 1} asks a negative speed")
            if problem := unreachable_target(rig, target):
                raise SafetyError(f"{protocol.name}: step {step.index + 1}: {problem} ({rig.path}); "
                                  "nothing was started")


def format_plan(protocol: ProtocolDef, rig: Rig, steps: list[Step], done: set[int] | None = None) -> str:
    """The dry-run table: one line per step with targets in RPM and an estimated duration."""
    done = done or set()
    lines = [f"{protocol.name} on {rig.name} ({rig.path}): {len(steps)} steps, "
             f"limit {rad_s_to_rpm(rig.limits.max_speed_rad_s):.0f} RPM"]
    total = 0.0
    for s in steps:
        targets = ", ".join(f"{k} {rad_s_to_rpm(v):.0f} RPM" for k, v in s.targets_rad_s.items())
        mark = "done " if s.index in done else ""
        total += 0 if s.index in done else s.est_duration_s
        lines.append(f"  {s.index + 1:3d}. {mark}{s.label:<28s} {targets:<24s} ~{s.est_duration_s:.0f} s")
    lines.append(f"estimated time: {total / 60:.1f} min; all targets within the rig's limits")
    return "\n".join(lines)
