"""One protocol of ``labkit twin`` on the model plant, in its own emulation (the twin's rows
come from :mod:`labkit.twin.run` and :mod:`labkit.twin.camera`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def run_protocol(rig_file: Path, protocol: str, sets: list[str], sessions: Path, seed: int) -> Any:
    """Run ``protocol`` on ``rig_file`` (a twin rig) on the virtual clock in a fresh, seeded
    emulation; the completed outcome, else LabkitError naming the protocol and why."""
    from labkit.emulators.plant import Emulation, use_emulation
    from labkit.errors import LabkitError
    from labkit.protocols.launch import execute, prepare_run
    with use_emulation(Emulation(f"twin-{protocol}", seed=seed)):
        prep = prepare_run(rig_file, protocol, sets, clock="virtual", session_root=sessions)
        outcome = execute(prep, sessions, notes="labkit twin")
    if outcome.status != "completed":
        raise LabkitError(f"labkit twin: {protocol} on the model plant {outcome.status}: {outcome.reason}")
    return outcome
