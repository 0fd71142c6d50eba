"""Loading the data a fit needs: a CSV with a header row, a results JSON, or a session directory.

A session directory holds ``results.json`` ``{"protocol", "points": [{...}, ...], "fit": {...}}``
and ``run.json`` (rig and run metadata). A results JSON may also be a bare list of point
objects. Columns keep the names of the file; units are in the names (``speed_rpm``,
``force_g``) and :func:`to_si` converts them by suffix.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from labkit.errors import DataFileError
from labkit.units import G0, RAD_S_PER_RPM

SI_FACTORS = {  # suffix -> (SI suffix, factor)
    "_rpm": ("_rad_s", RAD_S_PER_RPM),
    "_hz": ("_rad_s", 2.0 * math.pi),
    "_g": ("_n", G0 * 1e-3),
    "_mm": ("_m", 1e-3),
    "_deg": ("_rad", math.pi / 180.0),
}


@dataclass
class Table:
    """Columns of one data source. ``numeric`` holds float arrays (NaN for blanks),
    ``text`` the columns that are not numbers (e.g. ``series``), ``meta`` run and result
    metadata (``protocol``, ``run``, ``fit`` from the session), ``source`` the path."""

    source: str
    numeric: dict[str, np.ndarray]
    text: dict[str, list[str]] = field(default_factory=dict)
    meta: dict = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        return list(self.numeric) + list(self.text)

    def __len__(self) -> int:
        for col in self.numeric.values():
            return len(col)
        for col in self.text.values():
            return len(col)
        return 0

    def subset(self, mask: np.ndarray) -> Table:
        idx = np.flatnonzero(mask)
        return Table(self.source, {k: v[idx] for k, v in self.numeric.items()},
                     {k: [v[i] for i in idx] for k, v in self.text.items()}, self.meta)


def to_si(name: str, values: np.ndarray) -> tuple[str, np.ndarray]:
    """Convert a column to SI by its unit suffix: ``speed_rpm`` -> (``speed_rad_s``, rad/s)."""
    for suffix, (si_suffix, factor) in SI_FACTORS.items():
        if name.endswith(suffix):
            return name[: -len(suffix)] + si_suffix, np.asarray(values, dtype=float) * factor
    return name, np.asarray(values, dtype=float)


def load_table(path: str | Path) -> Table:
    """Load a CSV, a results JSON or a session directory (``results.json`` inside)."""
    path = Path(path)
    if path.is_dir():
        results = path / "results.json"
        if not results.exists():
            raise DataFileError(str(path), "", "not a session directory: no results.json inside "
                                "(did the run finish? `labkit run --resume` completes it)")
        table = _load_json(results)
        run = path / "run.json"
        if run.exists():
            try:
                table.meta["run"] = json.loads(run.read_text())
            except json.JSONDecodeError as exc:
                raise DataFileError(str(run), "", f"invalid JSON ({exc.msg} at line {exc.lineno})") from None
        table.meta["session"] = str(path)
        return table
    if not path.exists():
        raise DataFileError(str(path), "", "no such file or directory")
    if path.suffix.lower() == ".json":
        return _load_json(path)
    return _load_csv(path)


def _load_csv(path: Path) -> Table:
    with path.open(newline="") as fh:
        rows = list(csv.reader(line for line in fh if not line.lstrip().startswith("#")))
    if not rows or not any(cell.strip() for cell in rows[0]):
        raise DataFileError(str(path), "", "empty file: a CSV with a header row is expected")
    header = [h.strip() for h in rows[0]]
    body = [r for r in rows[1:] if any(c.strip() for c in r)]
    for i, r in enumerate(body, start=2):
        if len(r) != len(header):
            raise DataFileError(str(path), f"line {i}", f"{len(r)} fields, header has {len(header)}")
    cols = {h: [r[j].strip() for r in body] for j, h in enumerate(header)}
    return _columns_to_table(str(path), cols, {})


def _load_json(path: Path) -> Table:
    try:
        doc = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise DataFileError(str(path), "", f"invalid JSON ({exc.msg} at line {exc.lineno})") from None
    meta: dict = {}
    if isinstance(doc, dict):
        points = doc.get("points")
        if not isinstance(points, list):
            raise DataFileError(str(path), "points", "expected a list of point objects "
                                '({"protocol", "points": [...], "fit": {...}})')
        meta = {k: v for k, v in doc.items() if k != "points"}
    elif isinstance(doc, list):
        points = doc
    else:
        raise DataFileError(str(path), "", "expected an object with 'points' or a list of points")
    names: list[str] = []
    for i, p in enumerate(points):
        if not isinstance(p, dict):
            raise DataFileError(str(path), f"points[{i}]", "each point must be an object")
        for k in p:
            if k not in names:
                names.append(k)
    cols = {k: [p.get(k) for p in points] for k in names}
    return _columns_to_table(str(path), cols, meta)


def _columns_to_table(source: str, cols: dict[str, list], meta: dict) -> Table:
    numeric: dict[str, np.ndarray] = {}
    text: dict[str, list[str]] = {}
    for name, values in cols.items():
        parsed = [_as_float(v) for v in values]
        if all(p is not None for p in parsed):
            numeric[name] = np.array(parsed, dtype=float)
        elif all(not isinstance(v, dict | list) for v in values):
            text[name] = ["" if v is None else str(v) for v in values]
    return Table(source, numeric, text, meta)


def _as_float(v) -> float | None:
    if v is None or v == "":
        return math.nan
    if isinstance(v, bool):
        return None
    if isinstance(v, int | float):
        return float(v)
    if isinstance(v, str):
        s = v.strip().lower()
        if s in ("nan", "na", "n/a", "null"):
            return math.nan
        try:
            return float(s)
        except ValueError:
            return None
    return None
