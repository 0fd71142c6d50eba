"""``replay://ROLE.jsonl?mode=faithful``: a real-clock frame cassette served as the camera
delivered it (docs/explanation/replay.md, docs/decisions/0019-faithful-replay.md).

The faithful level of ``labkit replay`` runs the protocol again on a
:class:`~labkit.io.replay_clock.ReplayClock` started at the recording's clock reading; the
serial ports serve their cassettes at their recorded times (:mod:`labkit.io.faithful_port`).
This source does the same for a camera, for any protocol that takes bursts
(:meth:`labkit.devices.camera.device.Camera.burst`):

* **Frames at their recorded times.** Frames are served in their recorded order, each at its
  recorded arrival time (``t_host`` in the frame cassette, a clock reading of the recording):
  a read before it waits on the replay's clock until then (the speed loop and the tachometer's
  reader run on the way, as they did while the recording's camera exposed and sent the
  frame); a read after it gets the frame at once (the replayed program reached the burst later
  than the recorded one: counted, with the largest lateness, in :meth:`report`). Each frame
  keeps its recorded times, sequence number, drops and ``meta``, and its bytes are the
  camera's own JPEG, so an analysis of a replayed burst sees exactly what the run analysed.
* **Bursts matched by their label.** A burst is the recording's next one only if it carries
  the same label (the protocol's step and take, ``"2.0"``) and asks for as many frames;
  otherwise the replayed run took another decision than the recorded one, and
  :class:`~labkit.errors.ReplayMismatch` says which burst the replay took and which the
  recording took next, in the protocol's terms (step and take), with the cassette's line.
* **Faults as recorded.** A burst the recorded camera failed (its frame cassette's fault line,
  after the frames it did send) fails again at its recorded time with the recorded fault, so the
  replayed run ends, or goes on, as the recorded one did.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from labkit.devices.camera.cassette import ReplaySource, is_fault
from labkit.devices.camera.sources import RawFrame
from labkit.errors import ReplayMismatch

#: frames served this much (s) or more after their recorded time count as served late
LATE_S = 1e-6


def burst_words(label: Any) -> str:
    """A burst's label in a physicist's words: ``"2.1"`` -> ``step 2 (take 1)``."""
    found = re.fullmatch(r"(\d+)\.(\d+)", str(label))
    if found:
        return f"step {found.group(1)} (take {found.group(2)})"
    return "a burst without a step label" if label is None else f"burst {label!r}"


class FaithfulFrameSource(ReplaySource):
    """A frame cassette served at its recorded times, burst by burst (module docstring)."""

    def __init__(self, index: str | Path) -> None:
        super().__init__(index, "faithful")
        self.bursts = 0
        self.faults = 0
        self.late = 0
        self.latest_s = 0.0

    def begin_burst(self, n: int, label: Any) -> None:
        """The run starts a burst of ``n`` frames labelled ``label``: the recording's next burst
        must be the same (label and length), else :class:`ReplayMismatch`."""
        start = self.next
        if start >= len(self.entries):
            raise ReplayMismatch(f"camera cassette {self.path}: the replayed run took a burst of {n} frames "
                                 f"at {burst_words(label)}, but the recording took no more bursts "
                                 f"(all {sum(not is_fault(e) for e in self.entries)} frames served)")
        recorded = self.entries[start].get("step")
        length, failed = 0, False
        while start + length < len(self.entries) and self.entries[start + length].get("step") == recorded:
            if is_fault(self.entries[start + length]):
                failed = True  # the burst the camera failed: its frames, then the fault
                break
            length += 1
        if str(recorded) != str(label) or (length < n and not failed):
            line = start + 2  # the header is line 1
            raise ReplayMismatch(
                f"camera cassette {self.path}: the replayed run took a burst of {n} frames at "
                f"{burst_words(label)}, but the recording's next burst was {length} frames at "
                f"{burst_words(recorded)} (frame cassette line {line}): the run decided otherwise "
                "than the recorded one before this burst")
        self.bursts += 1
        self.faults += failed

    def read(self, timeout_s: float) -> RawFrame:
        due = float(self.entries[self.next]["t_host"]) if self.next < len(self.entries) else None
        if due is not None:
            now = self.clock.now()
            if now < due:
                self.clock.sleep_until(due)  # the camera delivered it then
            elif now - due >= LATE_S:
                self.late += 1
                self.latest_s = max(self.latest_s, now - due)
        return super().read(timeout_s)

    def report(self) -> dict[str, Any]:
        """What the replay served: frames and bursts of the recording's, how many late and by how much."""
        frames = [not is_fault(e) for e in self.entries]
        return {"port": Path(self.path).stem, "frames_recorded": sum(frames),
                "frames_served": sum(frames[:self.next]), "bursts": self.bursts, "failed_bursts": self.faults,
                "served_late": self.late, "latest_s": round(self.latest_s, 6)}
