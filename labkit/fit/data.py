"""Loading the data a fit needs: a CSV with a header row, a results JSON, a session directory,
or the JSON of ``labkit analyse laser|strobe`` (one clip = one row).

A session directory holds ``results.json`` ``{"protocol", "points": [{...}, ...], "fit": {...}}``
and ``run.json`` (rig and run metadata). A results JSON may also be a bare list of point
objects. Columns keep the names of the file; units are in the names (``speed_rpm``,
``force_gf``; the older ``force_g`` is read as grams-force too) and :func:`to_si` converts
them by suffix (labkit/units.py).

An analysis JSON (recognised by its keys, see :func:`analysis_kind`) becomes the row
``speed_rpm`` (its ``rotor_speed_rpm``), ``cone_angle_rad`` (laser ``tilt_rad.major``, strobe
``tilt_amplitude_rad``), ``cone_angle_minor_rad`` (laser ``tilt_rad.minor``), ``spin_rad_s``
when recorded, and the text columns ``kind`` and ``source_file``: the cone angle against rotor
speed of Eq. 5.24 (Eq. 5.68 with spin). :func:`load_tables` joins several inputs (files,
folders of analysis JSON, glob patterns) row by row.
"""

from __future__ import annotations

import csv
import glob
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from labkit.errors import DataFileError
from labkit.units import column_to_si

#: The largest data file read (CSV or JSON); a bigger one is refused before it is read.
MAX_DATA_FILE_BYTES = 256_000_000



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
    """Convert a column to SI by its unit suffix (the table of labkit/units.py):
    ``speed_rpm`` -> (``speed_rad_s``, rad/s); ``force_gf`` (and the older ``force_g``,
    grams-force) -> ``force_n``."""
    si_name, factor = column_to_si(name)
    return si_name, np.asarray(values, dtype=float) * factor


def load_table(path: str | Path) -> Table:
    """Load a CSV, a results JSON or a session directory (``results.json`` inside)."""
    path = Path(path)
    if path.is_dir():
        results = _inside(path, "results.json")
        if not results.exists():
            analyses = _analysis_files(path)
            if analyses:
                return _load_analysis_folder(path, analyses)
            table = _session_without_results(path)
        else:
            table = _load_json(results)
        run = _inside(path, "run.json")
        if run.exists():
            table.meta["run"] = _read_json(run)
        table.meta["session"] = str(path)
        return table
    if not path.exists():
        raise DataFileError(str(path), "", "no such file or directory")
    if path.suffix.lower() == ".json":
        return _load_json(path)
    return _load_csv(path)


def _session_without_results(path: Path) -> Table:
    """A session folder without results.json: its results from events.jsonl
    (:mod:`labkit.protocols.recover`), said on stderr; refused when there are none."""
    import sys

    from labkit.errors import LabkitError
    from labkit.session import load_session_record
    from labkit.session.recover import results_from_events

    if not _inside(path, "run.json").exists():
        raise DataFileError(str(path), "", "not a session directory: no results.json inside (nor run.json), "
                            "and no `labkit analyse --json` files either")
    try:
        record = load_session_record(path)
        found = results_from_events(record)
    except LabkitError as exc:
        raise DataFileError(str(path), "results.json", f"missing, and the session cannot be read: {exc}") \
            from None
    if found is None:
        raise DataFileError(str(path), "results.json", "missing, and events.jsonl holds no point: the run "
                            "ended before its first step was measured (`labkit run --resume` measures them)")
    results, where = found
    print(f"labkit: {path}: results.json is missing (deleted, or the run was killed after its last point); "
          f"using {where}", file=sys.stderr)
    return _table_from_doc(results, str(path / "events.jsonl"))


def _inside(session: Path, name: str) -> Path:
    """``session/name``, refused (DataFileError) when a symlink leads it out of the session."""
    from labkit.errors import SessionError
    from labkit.session.paths import session_file

    try:
        return session_file(session, name)
    except SessionError as exc:
        raise DataFileError(str(session / name), "", str(exc)) from None


def _read_bounded(path: Path) -> bytes:
    """The bytes of a data file, at most :data:`MAX_DATA_FILE_BYTES`; DataFileError otherwise."""
    try:
        if not path.is_file():
            raise DataFileError(str(path), "", "not a regular file")
        with path.open("rb") as fh:
            data = fh.read(MAX_DATA_FILE_BYTES + 1)
    except OSError as exc:
        raise DataFileError(str(path), "", f"cannot read: {exc.strerror or exc}") from None
    if len(data) > MAX_DATA_FILE_BYTES:
        raise DataFileError(str(path), "", f"larger than {MAX_DATA_FILE_BYTES // 1_000_000} MB")
    return data


def _read_text(path: Path) -> str:
    data = _read_bounded(path)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise DataFileError(str(path), f"line {line}", f"not UTF-8 text (byte {exc.start})") from None


def _load_csv(path: Path) -> Table:
    text = _read_text(path)
    if "\x00" in text:
        line = text.count("\n", 0, text.index("\x00")) + 1
        raise DataFileError(str(path), f"line {line}", "contains a NUL byte: not a text CSV")
    reader = csv.reader(line for line in text.splitlines(keepends=True) if not line.lstrip().startswith("#"))
    try:
        rows = list(reader)
    except csv.Error as exc:
        raise DataFileError(str(path), f"row {reader.line_num}", f"not a readable CSV ({exc})") from None
    if not rows or not any(cell.strip() for cell in rows[0]):
        raise DataFileError(str(path), "", "empty file: a CSV with a header row is expected")
    header = [h.strip() for h in rows[0]]
    body = [r for r in rows[1:] if any(c.strip() for c in r)]
    for i, r in enumerate(body, start=2):
        if len(r) != len(header):
            raise DataFileError(str(path), f"line {i}", f"{len(r)} fields, header has {len(header)}")
    cols = {h: [r[j].strip() for r in body] for j, h in enumerate(header)}
    return _columns_to_table(str(path), cols, {})


def _read_json(path: Path):
    """A JSON document, bounded in size and nesting; DataFileError naming the file otherwise."""
    from labkit.session.reader import parse_json_bytes

    try:
        return parse_json_bytes(_read_bounded(path))
    except ValueError as exc:
        raise DataFileError(str(path), "", f"invalid JSON: {exc}") from None


read_json = _read_json


def _try_json(path: Path):
    """The JSON of ``path``, or None when it is unreadable (its loader names the problem later)."""
    try:
        return _read_json(path)
    except DataFileError:
        return None


def _load_json(path: Path) -> Table:
    return _table_from_doc(_read_json(path), str(path))


def _table_from_doc(doc: Any, source: str) -> Table:
    """A table from a results document (results.json's, or one recovered from events.jsonl)."""
    meta: dict = {}
    if analysis_kind(doc):
        row = analysis_row(doc, source)
        return _columns_to_table(source, {k: [v] for k, v in row.items()},
                                 {"analysis": row["kind"], "video": doc.get("source")})
    if isinstance(doc, dict):
        points = doc.get("points")
        if not isinstance(points, list):
            raise DataFileError(source, "points", "expected a list of point objects "
                                '({"protocol", "points": [...], "fit": {...}})')
        meta = {k: v for k, v in doc.items() if k != "points"}
    elif isinstance(doc, list):
        points = doc
    else:
        raise DataFileError(source, "", "expected an object with 'points' or a list of points")
    names: list[str] = []
    for i, p in enumerate(points):
        if not isinstance(p, dict):
            raise DataFileError(source, f"points[{i}]", "each point must be an object")
        for k in p:
            if k not in names:
                names.append(k)
    cols = {k: [p.get(k) for p in points] for k in names}
    return _columns_to_table(source, cols, meta)


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


# --- `labkit analyse laser|strobe --json` files: one clip, one row (cone angle vs rotor speed) ---

LASER_KEYS = frozenset({"pattern", "tilt_rad", "quality"})
STROBE_KEYS = frozenset({"tilt_amplitude_rad", "lateral_amplitude_px", "phase_source"})


def analysis_kind(doc) -> str | None:
    """``"laser"`` or ``"strobe"`` when ``doc`` is the JSON of ``labkit analyse laser|strobe``
    (recognised by its keys), else None."""
    if not isinstance(doc, dict) or "points" in doc:
        return None
    if LASER_KEYS <= doc.keys():
        return "laser"
    if STROBE_KEYS <= doc.keys():
        return "strobe"
    return None


def analysis_row(doc: dict, file: str) -> dict[str, float | str]:
    """The fit row of one analysed clip: ``speed_rpm``, ``cone_angle_rad`` (laser
    ``tilt_rad.major``, strobe ``tilt_amplitude_rad``), ``cone_angle_minor_rad`` (laser),
    ``spin_rad_s`` when recorded, ``kind`` and ``source_file``; the points of Eq. 5.24 / 5.68.

    Raises :class:`DataFileError` naming ``file`` and what is missing: the rotor speed (analysed
    without ``--speed-rpm``) or the tilt (laser without ``--screen-distance-mm``/``--mm-per-px``,
    or no trace found).
    """
    kind = analysis_kind(doc)
    if kind is None:
        raise DataFileError(file, "", "not a `labkit analyse laser|strobe --json` result")
    video = doc.get("source") or "CLIP"
    speed = doc.get("rotor_speed_rpm")
    if speed is None:
        raise DataFileError(file, "rotor_speed_rpm", "no rotor speed recorded (analysed without "
                            f"--speed-rpm); rerun `labkit analyse {kind} {video} ... --speed-rpm RPM`")
    speed = _finite_number(file, "rotor_speed_rpm", speed)
    if kind == "laser":
        tilt = doc.get("tilt_rad")
        if not tilt:
            pattern = doc.get("pattern") or {}
            if pattern.get("type") == "none":
                why = f"no trace in the clip (pattern none: {pattern.get('reason', 'no reason given')})"
            else:
                why = (f"no tilt: analysed without --screen-distance-mm and --mm-per-px; rerun "
                       f"`labkit analyse laser {video} --screen-distance-mm L --mm-per-px S ...`")
            raise DataFileError(file, "tilt_rad", why)
        if not isinstance(tilt, dict):
            raise DataFileError(file, "tilt_rad", "expected an object with 'major' and 'minor'")
        row: dict[str, float | str] = {
            "speed_rpm": speed,
            "cone_angle_rad": _finite_number(file, "tilt_rad.major", tilt.get("major")),
            "cone_angle_minor_rad": _finite_number(file, "tilt_rad.minor", tilt.get("minor")),
        }
    else:
        row = {"speed_rpm": speed,
               "cone_angle_rad": _finite_number(file, "tilt_amplitude_rad", doc.get("tilt_amplitude_rad"))}
    if doc.get("spin_rad_s") is not None:
        row["spin_rad_s"] = _finite_number(file, "spin_rad_s", doc["spin_rad_s"])
    row["kind"] = kind
    row["source_file"] = file
    return row


def _finite_number(file: str, key: str, value) -> float:
    try:
        number = None if isinstance(value, bool) or not isinstance(value, int | float) else float(value)
    except OverflowError:  # an integer beyond the float range
        number = None
    if number is None or not math.isfinite(number):
        shown = json.dumps(value)
        raise DataFileError(file, key, f"expected a finite number, got {shown[:40]}")
    return number


def _analysis_files(folder: Path) -> list[Path]:
    """The analysis JSON files directly in ``folder`` (others, e.g. ``.truth.json``, are left out)."""
    out = []
    for p in sorted(folder.glob("*.json")):
        doc = _try_json(p)
        if analysis_kind(doc):
            out.append(p)
    return out


def _load_analysis_folder(folder: Path, files: list[Path]) -> Table:
    others = sorted({p.name for p in folder.glob("*.json")} - {p.name for p in files})
    table = _join([load_table(p) for p in files], str(folder))
    table.meta["skipped"] = others
    return table


def expand_inputs(inputs: Sequence[str | Path]) -> list[Path]:
    """Paths as given; a pattern with ``*``, ``?`` or ``[`` that is not an existing path is
    expanded (sorted). Raises :class:`DataFileError` for a pattern that matches nothing."""
    out: list[Path] = []
    for item in inputs:
        text = str(item)
        if not Path(text).exists() and any(c in text for c in "*?["):
            matches = sorted(glob.glob(text))
            if not matches:
                raise DataFileError(text, "", "no file matches this pattern")
            out.extend(Path(m) for m in matches)
        else:
            out.append(Path(text))
    return out


def load_tables(inputs: Sequence[str | Path]) -> Table:
    """Load several inputs (files, folders, glob patterns) and join them row by row.

    One plain input gives :func:`load_table`'s table unchanged. Otherwise a column missing
    from one input is blank (NaN, or "" for text) in its rows, and a ``source_file`` column
    names each row's file. Analysis JSONs must agree on spin: either every clip records
    ``spin_rad_s`` or none does (a :class:`DataFileError` names the clips without it). Other
    JSON files among analysis JSONs (e.g. ``.truth.json``) are left out and listed in
    ``meta["skipped"]``.
    """
    paths = expand_inputs(inputs)
    if not paths:
        raise DataFileError("", "", "no input given")
    if len(paths) == 1:
        return load_table(paths[0])
    kept, skipped = _leave_out_stray_json(paths)
    table = _join([load_table(p) for p in kept], _describe(kept))
    if skipped:
        table.meta["skipped"] = [str(p) for p in skipped]
    return table


def _leave_out_stray_json(paths: list[Path]) -> tuple[list[Path], list[Path]]:
    """Among analysis JSONs (``clips/*.json``), JSON files that are neither analysis results nor
    results tables (``labkit synth`` ``.truth.json``, a fit's ``--json`` output) are left out, as
    in a folder; they are listed, never dropped unseen. Without analysis JSONs nothing is left out."""
    kinds = {}
    for p in paths:
        if p.suffix.lower() == ".json" and p.is_file():
            doc = _try_json(p)
            if doc is None:
                continue  # load_table names the problem
            kinds[p] = "analysis" if analysis_kind(doc) else (
                "table" if isinstance(doc, list) or (isinstance(doc, dict) and "points" in doc) else "other")
    if "analysis" not in kinds.values():
        return paths, []
    return [p for p in paths if kinds.get(p) != "other"], [p for p in paths if kinds.get(p) == "other"]


def _describe(paths: Sequence[Path]) -> str:
    names = [str(p) for p in paths]
    if len(names) <= 3:
        return ", ".join(names)
    return f"{names[0]} ... {names[-1]} ({len(names)} files)"


def _join(tables: list[Table], source: str) -> Table:
    _check_spin_recorded(tables)
    numeric_names: list[str] = []
    text_names: list[str] = []
    for t in tables:
        numeric_names += [n for n in t.numeric if n not in numeric_names]
        text_names += [n for n in t.text if n not in text_names]
    if "source_file" not in text_names:
        text_names.append("source_file")
    as_text = [n for n in numeric_names if n in text_names]  # numbers in one file, words in another
    numeric_names = [n for n in numeric_names if n not in as_text]
    numeric = {n: np.concatenate([t.numeric.get(n, np.full(len(t), math.nan)) for t in tables])
               for n in numeric_names}
    text: dict[str, list[str]] = {}
    for n in text_names:
        text[n] = []
        for t in tables:
            if n in t.text:
                text[n] += t.text[n]
            elif n in t.numeric:
                text[n] += ["" if math.isnan(v) else f"{v:.10g}" for v in t.numeric[n]]
            elif n == "source_file":
                text[n] += [t.source] * len(t)
            else:
                text[n] += [""] * len(t)
    meta = {"inputs": [t.source for t in tables]}
    return Table(source, numeric, text, meta)


def _check_spin_recorded(tables: list[Table]) -> None:
    clips = [t for t in tables if t.meta.get("analysis")]
    without = [t.source for t in clips if "spin_rad_s" not in t.numeric]
    if without and len(without) < len(clips):
        shown = ", ".join(without[:3]) + (f" and {len(without) - 3} more" if len(without) > 3 else "")
        raise DataFileError(without[0], "spin_rad_s",
                            f"{len(clips) - len(without)} of {len(clips)} clips record the floator spin and "
                            f"{len(without)} do not ({shown}); give --spin-rad-s to `labkit analyse` for "
                            "every clip or for none (Eq. 5.68 needs it per point)")


def write_table(table: Table, path: str | Path) -> Path:
    """Write ``table`` as a CSV with a header row (numeric columns first, blanks for NaN) that
    :func:`load_table` reads back; a ``#`` comment line names the source."""
    path = Path(path)
    names = list(table.numeric) + list(table.text)
    rows = []
    for i in range(len(table)):
        row = ["" if math.isnan(v[i]) else f"{v[i]:.10g}" for v in table.numeric.values()]
        rows.append(row + [v[i] for v in table.text.values()])
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("w", newline="") as fh:
            fh.write(f"# collected by labkit fit from {table.source}\n")
            writer = csv.writer(fh)
            writer.writerow(names)
            writer.writerows(rows)
    except OSError as exc:
        raise DataFileError(str(path), "", f"cannot write the table: {exc.strerror}") from None
    return path
