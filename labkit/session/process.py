"""Which process wrote a session: an identity no later process with the same PID shares, so a
stale ``running`` session is closed only by its own worker's supervisor
(:mod:`labkit.session.orphans`, ADR 0031)."""

from __future__ import annotations

from pathlib import Path


def process_identity(pid: int) -> str | None:
    """``BOOT_ID:START_TICKS`` of a live process (Linux ``/proc``), which no later process with
    the same PID shares; None where it cannot be read (another system, the process gone)."""
    try:
        boot = Path("/proc/sys/kernel/random/boot_id").read_text().strip()
        stat = Path(f"/proc/{pid}/stat").read_text()
        start = stat[stat.rindex(")") + 2:].split()[19]  # field 22, after the command in parentheses
    except (OSError, ValueError, IndexError):
        return None
    return f"{boot}:{start}"
