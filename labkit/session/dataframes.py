"""A session as pandas DataFrames: ``labkit.load_session(PATH)`` (docs/how-to/script-labkit.md,
docs/tutorials/notebook.md).

Built on :func:`labkit.session.reader.load_session_record` (same bounds, same damaged-line reports).
Units are in the column names, always in the last ``_`` part:

* ``.points``: one row per measured step, the columns of ``results.json`` (or the ``point``
  events of a session cut short): ``speed_rpm``, ``speed_std_rpm``, ``force_g``,
  ``force_stderr_g``, ``force_n``, ``settle_time_s``, ... (``n``, ``step``, ``repeat`` and
  ``unstable`` are counts, ``direction`` is ``up``/``down``).
* ``.readings[role]``: every reading of one device, ``t_s`` (seconds since the run's start) and
  one column per quantity named ``QUANTITY_UNIT`` with ``/`` as ``_`` (``mass_kg`` for a balance,
  ``angular_speed_rad_s`` for a tachometer), then ``stable``, ``overload``, ``flags``, ``raw``.
* ``.events``: events.jsonl, ``t_s`` and ``type`` first, other keys as columns (NaN where absent).
* ``.meta``: run.json as a dict (protocol, params, rig, clock, versions).

pandas is imported here only, so ``import labkit`` stays fast.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from labkit.session.paths import session_file
from labkit.session.reader import SessionRecord, load_session_record

if TYPE_CHECKING:
    import pandas as pd


def column_unit(unit: str) -> str:
    """A unit as a column-name suffix: ``rad/s`` -> ``rad_s``, ``%`` -> ``pct``."""
    return unit.replace("/", "_").replace("%", "pct").replace(" ", "")


def readings_frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    """Readings (``t``, ``quantity``, ``value``, ``unit``, ...) with one ``QUANTITY_UNIT`` column each."""
    import pandas as pd

    records = []
    for row in rows:
        rec: dict[str, Any] = {"t_s": row.get("t")}
        name = str(row.get("quantity", "value"))
        unit = row.get("unit")
        rec[f"{name}_{column_unit(str(unit))}" if unit else name] = row.get("value")
        rec.update({k: row[k] for k in ("stable", "overload", "flags", "raw") if k in row})
        records.append(rec)
    return pd.DataFrame.from_records(records)


class Readings(Mapping[str, "pd.DataFrame"]):
    """``role -> DataFrame`` of ``readings/ROLE.jsonl``, read on first access."""

    def __init__(self, record: SessionRecord) -> None:
        self._record = record
        folder = record.path / "readings"
        self._roles = sorted(p.stem for p in folder.glob("*.jsonl")) if folder.is_dir() else []
        self._frames: dict[str, pd.DataFrame] = {}

    def __getitem__(self, role: str) -> pd.DataFrame:
        if role not in self._roles:
            raise KeyError(f"{role!r}: no readings/{role}.jsonl in {self._record.path} "
                           f"(roles: {', '.join(self._roles) or 'none'})")
        if role not in self._frames:
            session_file(self._record.path, "readings", f"{role}.jsonl")  # stays inside the session
            self._frames[role] = readings_frame(self._record.readings(role))
        return self._frames[role]

    def __iter__(self) -> Iterator[str]:
        return iter(self._roles)

    def __len__(self) -> int:
        return len(self._roles)


class SessionFrames:
    """One session read for analysis: ``.points``, ``.readings[role]``, ``.events``, ``.meta``."""

    def __init__(self, record: SessionRecord) -> None:
        self.record = record
        self.path: Path = record.path
        self.meta: dict[str, Any] = record.meta
        self.readings = Readings(record)
        #: ``file:line: reason`` of every damaged line skipped while reading
        self.problems: list[str] = record.problems

    @property
    def protocol(self) -> str:
        return self.record.protocol

    @property
    def points(self) -> pd.DataFrame:
        import pandas as pd

        results = self.record.results or {}
        rows = results.get("points") if results.get("points") is not None else self.record.completed_points()
        return pd.DataFrame.from_records(rows or [])

    @property
    def fit(self) -> dict[str, Any] | None:
        """The quick fit ``labkit run`` stored in results.json (None if the run did not finish)."""
        return (self.record.results or {}).get("fit")

    @property
    def events(self) -> pd.DataFrame:
        import pandas as pd

        frame = pd.DataFrame.from_records(self.record.events)
        if "t" in frame:
            frame = frame.rename(columns={"t": "t_s"})
        first = [c for c in ("t_s", "type") if c in frame]
        return frame[first + [c for c in frame.columns if c not in first]]

    def __repr__(self) -> str:
        return (f"SessionFrames({str(self.path)!r}, protocol={self.protocol!r}, "
                f"points={len(self.record.completed_points())}, readings={list(self.readings)})")


def load_session(path: str | Path) -> SessionFrames:
    """A session directory as DataFrames (see the module docstring for columns and units).

    Raises :class:`labkit.session.SessionError` (one line naming the file) if it is not a
    readable session."""
    return SessionFrames(load_session_record(path))
