"""``build_report(source, out)``: a self-contained folder with report.md, PNG figures, data.csv
and fits.json for a session directory, a results JSON, a CSV (with a model) or a video
analysis result.
"""

from __future__ import annotations

import csv
import datetime as _dt
import json
import math
from pathlib import Path

import numpy as np

from labkit import __version__
from labkit.errors import DataFileError, LabkitError
from labkit.fit.data import Table, load_table, read_json
from labkit.fit.overlay import Overlay
from labkit.fit.table_fit import FitReport, fit_table
from labkit.hints import HintsError
from labkit.protocols.legacy_hints import hints_for
from labkit.report import markdown as md
from labkit.report.figures import contact_sheet, fit_figure
from labkit.report.flags import flags_section
from labkit.report.plans import Plan, plan_for
from labkit.report.video import overlay, sample_frames
from labkit.units import split_suffix

MAX_TABLE_COLUMNS = 10


def floator_inertia(session: Path) -> float | None:
    """Radial (else axial) moment of inertia of the rig's floator (kg m^2) from the session's
    rig.toml. The floator table is validated by :func:`labkit.rig.parse_body`, so every unit a
    rig file accepts (``inertia_radial_g_mm2``...) works here too. None when the session has no
    readable rig, no floator or no inertia."""
    import tomllib

    from labkit.errors import RigFileError
    from labkit.rig import parse_body, read_rig_text

    rig_path = session / "rig.toml"
    if not rig_path.is_file():
        return None
    try:
        table = tomllib.loads(read_rig_text(rig_path)).get("bodies", {}).get("floator")
        if not isinstance(table, dict):
            return None
        floator = parse_body(str(rig_path), "floator", table)
    except (tomllib.TOMLDecodeError, RigFileError, RecursionError):
        return None
    return floator.inertia_radial_kg_m2 or floator.inertia_axial_kg_m2


def _check_output_folder(source: Path, out: Path) -> None:
    """The report folder holds no symbolic link and, inside a session, stays inside it: a
    session from elsewhere whose ``report/`` or ``report/report.md`` is a link would otherwise
    make the report overwrite the link's target (a file in the user's home, issue 27)."""
    from labkit.session.paths import session_file

    if source.is_dir() and out == default_out(source):
        if out.is_symlink():
            raise DataFileError(str(out), "", "is a symbolic link: labkit report writes no file through a "
                                "link (a session from elsewhere?); remove it or give --out")
        session_file(source, "report")
    if out.is_dir():
        for entry in out.iterdir():
            if entry.is_symlink():
                raise DataFileError(str(entry), "", "is a symbolic link: labkit report writes no file "
                                    "through a link (a session from elsewhere?); remove it or give --out")


def default_out(source: Path) -> Path:
    return source / "report" if source.is_dir() else source.with_name(source.stem + "-report")


def build_report(source: str | Path, out: str | Path | None = None, *, model: str | None = None,
                 x: str | None = None, y: str | None = None, inertia: float | None = None,
                 overlays: tuple[Overlay, ...] = ()) -> Path:
    """Write the report folder and return the path of its report.md.

    ``model`` (with optional ``x``/``y`` columns) replaces the automatic choice of fits;
    ``overlays`` (e.g. simulated curves, :mod:`labkit.fit.overlay`) are drawn on every fit figure.
    """
    source = Path(source)
    out = Path(out) if out is not None else default_out(source)
    if source.is_file() and source.suffix.lower() == ".json":
        doc = _read_json(source)
        if isinstance(doc, dict) and ("pattern" in doc or "point_pattern" in doc) and "points" not in doc:
            return _video_report(source, doc, out)
    table = load_table(source)
    if len(table) == 0:
        raise DataFileError(str(source), "points", "no data points to report")
    run = table.meta.get("run", {})
    protocol = table.meta.get("protocol") or run.get("protocol")
    if inertia is None and source.is_dir():
        inertia = floator_inertia(source)
    try:
        hints = hints_for(protocol, _start_hints(source), table.numeric)
    except HintsError as exc:
        raise DataFileError(str(source / "events.jsonl"), "hints", str(exc)) from None
    plan = plan_for(table, hints, inertia, model, x=x, y=y)
    _check_output_folder(source, out)
    out.mkdir(parents=True, exist_ok=True)
    lines = [f"# labkit report: {source.name}", "",
             f"Source: `{source}`  ", f"Generated: {_now()} by labkit {__version__}", ""]
    lines += _metadata_section(table, run, protocol, inertia)
    if source.is_dir():
        lines += _events_section(source / "events.jsonl")
        lines += flags_section(source)
    lines += _data_section(table, out)
    lines += _fit_sections(table, plan, out, overlays)
    (out / "report.md").write_text(md.writable("\n".join(lines) + "\n"), encoding="utf-8")
    return out / "report.md"


#: the longest first line of events.jsonl read for the start document's hints
MAX_START_LINE = 1_000_000


def declared_fit_model(source: Path, table: Table) -> str | None:
    """The ``labkit fit`` model a session (or a table of a known protocol) declares in its hints:
    the one ``labkit run``'s quick fit, the live fit and the report's first fit use; None when the
    input does not say (a plain CSV of unknown columns)."""
    run = table.meta.get("run", {})
    protocol = table.meta.get("protocol") or run.get("protocol")
    try:
        hints = hints_for(protocol, _start_hints(source), table.numeric)
    except HintsError as exc:
        raise DataFileError(str(source / "events.jsonl"), "hints", str(exc)) from None
    return hints.fit if hints is not None else None


def _start_hints(source: Path) -> dict | None:
    """The hints of a session's start document (first line of events.jsonl), None when the
    source is no session, the line is no start document or was written before ADR 0021."""
    path = source / "events.jsonl"
    if not (source.is_dir() and path.is_file()):
        return None
    with open(path, encoding="utf-8", errors="replace") as f:
        line = f.readline(MAX_START_LINE)
    try:
        start = json.loads(line)
    except ValueError:
        return None
    hints = start.get("hints") if isinstance(start, dict) and start.get("type") == "start" else None
    return hints if isinstance(hints, dict) else None


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def _read_json(path: Path):
    """Bounded in size and nesting; DataFileError naming the file (labkit.fit.data.read_json)."""
    return read_json(path)


def _metadata_section(table: Table, run: dict, protocol: str | None, inertia: float | None) -> list[str]:
    lines = ["## Rig and run", ""]
    rows = [["protocol", protocol or "(not given)"]]
    for key in ("rig", "status", "reason", "started", "ended", "clock", "notes", "git_commit",
                "resumed_from", "host"):
        if run.get(key) not in (None, ""):
            rows.append([key, run[key]])
    if run.get("params"):
        rows.append(["params", ", ".join(f"{k} = {_words(v)}" for k, v in sorted(run["params"].items()))])
    if run.get("versions"):
        rows.append(["versions", ", ".join(f"{k} {v}" for k, v in run["versions"].items())])
    rows.append(["floator inertia (kg m^2)", inertia if inertia else "not given"])
    quick = table.meta.get("fit")
    if isinstance(quick, dict) and quick.get("params"):
        ps = ", ".join(f"{k} = {md.num((v or {}).get('value'))}" for k, v in quick["params"].items()
                       if isinstance(v, dict))
        rows.append(["protocol's quick fit", f"{quick.get('model', '')}: {ps}"])
    lines += [md.table(["item", "value"], rows), ""]
    return lines


NOTABLE_EVENTS = ("interlock", "fault", "error", "drop", "reconnect", "stop")


def _events_section(path: Path) -> list[str]:
    """Event counts by type, and the notable ones (interlocks, faults, drops) listed."""
    if not path.is_file():
        return []
    from labkit.errors import SessionError
    from labkit.session.reader import read_jsonl

    counts: dict[str, int] = {}
    notable: list[dict] = []
    try:
        events = read_jsonl(path)  # bounded; damaged lines (and a line cut by a crash) skipped
    except SessionError:
        return []
    for ev in events:
        kind = str(ev.get("type", "?"))
        counts[kind] = counts.get(kind, 0) + 1
        if any(k in kind for k in NOTABLE_EVENTS) and len(notable) < 20:
            notable.append(ev)
    lines = ["## Events", "", md.table(["event", "count"], [[k, v] for k, v in sorted(counts.items())]), ""]
    if notable:
        lines += ["Notable events:", ""]
        lines += [f"- {event_in_words(ev)}" for ev in notable]
        lines.append("")
    return lines


def _words(value) -> str:
    """A value as text: numbers to 5 significant digits, lists joined, no JSON."""
    if isinstance(value, list | tuple):
        return ", ".join(_words(v) for v in value)
    if isinstance(value, dict):
        return "; ".join(f"{k} {_words(v)}" for k, v in value.items())
    return md.num(value)


def event_in_words(ev: dict) -> str:
    """One line for a notable event: when, what, and its numbers with units."""
    kind = str(ev.get("type", "?"))
    when = f"{float(ev['t']):.2f} s" if isinstance(ev.get("t"), int | float) else "?"
    if kind == "drop":
        text = (f"the floator dropped ({ev.get('cause', 'cause not recorded')}) at rotor "
                f"{md.num(ev.get('rotor_rad_s'), 4)} rad/s, spin {md.num(ev.get('spin_rad_s'), 4)} rad/s")
    elif kind in ("interlock", "fault"):
        text = f"{kind}: {ev.get('reason', 'no reason recorded')}; motors set to zero"
    elif kind == "stop":
        reason = f" ({ev['reason']})" if ev.get("reason") else ""
        text = f"run {ev.get('status', 'ended')} after {ev.get('steps_done', '?')} steps{reason}"
    else:
        rest = {k: v for k, v in ev.items() if k not in ("type", "t")}
        text = kind.replace("_", " ") + (": " + _words(rest) if rest else "")
    return f"{when}: {text}"


def spread_column(table: Table, column: str) -> np.ndarray | None:
    """The recorded spread of a column: ``force_g`` -> ``force_stderr_g`` (or ``_std_``),
    ``speed_rpm`` -> ``speed_std_rpm``, ``spin_rad_s`` -> ``spin_std_rad_s``; None when the
    session has none."""
    head, unit = split_suffix(column) or column.rpartition("_")[::2]
    for kind in ("stderr", "std"):
        name = f"{head}_{kind}_{unit}" if head else ""
        if name in table.numeric:
            return np.asarray(table.numeric[name], dtype=float)
    return None


def _errors(table: Table, report: FitReport) -> dict[str, tuple[np.ndarray | None, np.ndarray | None]]:
    """Per series, the x and y spreads of its points, matched to the table rows by value."""
    out = {}
    for name, res in report.series.items():
        pair = []
        for col, values in ((res.x_name, res.x), (res.y_name, res.y)):
            spread = spread_column(table, col) if col in table.numeric else None
            if spread is None:
                pair.append(None)
                continue
            column = np.asarray(table.numeric[col], dtype=float)
            rows = [int(np.argmin(np.abs(column - v))) for v in np.asarray(values, dtype=float)]
            err = np.where(np.isfinite(spread[rows]), spread[rows], 0.0)
            pair.append(err)
        out[name] = (pair[0], pair[1])
    return out


def _data_section(table: Table, out: Path) -> list[str]:
    names = list(table.numeric) + list(table.text)
    with (out / "data.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for i in range(len(table)):
            w.writerow([_cell(table, n, i) for n in names])
    shown = names[:MAX_TABLE_COLUMNS]
    rows = [[_cell(table, n, i) for n in shown] for i in range(len(table))]
    more = f" ({len(names) - len(shown)} more columns in data.csv)" if len(names) > len(shown) else ""
    return ["## Data", "", f"{len(table)} rows; full table: [data.csv](data.csv){more}", "",
            md.table(shown, rows), ""]


def _cell(table: Table, name: str, i: int):
    if name in table.numeric:
        v = float(table.numeric[name][i])
        return v if np.isfinite(v) else ""
    return table.text[name][i]


def _fit_sections(table: Table, plan: Plan, out: Path, overlays: tuple[Overlay, ...]) -> list[str]:
    if not plan.fits:
        return ["## Fits", "", "No model applies to these columns; use `labkit report --model NAME`.", ""]
    lines = ["## Fits", ""]
    lines += [f"{n}  " for n in plan.notes] + ([""] if plan.notes else [])
    done: list[tuple[str, FitReport]] = []
    fits_json = {}
    for pf in plan.fits:
        lines += [f"### {pf.title}", ""]
        if pf.note:
            lines += [pf.note.strip(), ""]
        try:
            report = fit_table(table, pf.model, pf.options)
        except LabkitError as exc:
            lines += [f"**Not fitted:** {exc}", ""]
            continue
        done.append((pf.title, report))
        fits_json[pf.slug] = report.to_json()
        fig = fit_figure(report, out / f"fig-{pf.slug}.png", overlays=(*pf.overlays, *overlays),
                         title=pf.figure_title or pf.title, errors=_errors(table, report), svg=True)
        lines += [f"![{pf.title}]({fig.name})", "", f"Vector version: [{fig.stem}.svg]({fig.stem}.svg)", ""]
        for name, res in report.series.items():
            if len(report.series) > 1 or name != "all":
                lines += [f"**Series {name}**", ""]
            lines += [md.param_table(res), "", md.quality_line(res), ""]
            lines += [f"> **Warning:** {w}" for w in res.warnings]
            if res.warnings:
                lines.append("")
    (out / "fits.json").write_text(json.dumps(fits_json, indent=2) + "\n")
    if len(done) > 1:
        lines += _comparison(done)
    return lines


def aicc(aic: float, n: int, k: int) -> float:
    """AIC corrected for few points (Hurvich & Tsai): ``AIC + 2k(k+1)/(n-k-1)``; infinite when
    ``n <= k + 1`` (the model has too few points left over to be compared)."""
    return aic + 2.0 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else math.inf


def _comparison(done: list[tuple[str, FitReport]]) -> list[str]:
    rows = []
    series = sorted({s for _, r in done for s in r.series})
    for s in series:
        entries = [(t, r.series[s]) for t, r in done if s in r.series]
        scores = [aicc(res.aic, res.n, len(res.fitted_names)) for _, res in entries]
        best = min(scores)
        for (title, res), score in zip(entries, scores, strict=True):
            comparable = math.isfinite(score)
            rows.append([s, title, len(res.fitted_names), res.n, md.num(res.rms_residual, 4),
                         res.residual_space, md.num(score, 4) if comparable else "n/a (too few points)",
                         md.num(score - best, 3) if comparable and math.isfinite(best) else "",
                         "yes" if comparable and score == best else "", len(res.warnings)])
    return ["## Model comparison", "",
            "Models of one data set are fitted in the same residual space; lower AICc (AIC corrected "
            "for few points) is better (a difference above ~2 is meaningful, above ~10 decisive). A "
            "model with no more than one point beyond its fitted parameters cannot be compared: "
            "with 3 points, a 2-parameter fit always looks better by plain AIC. The first fit above "
            "is the protocol's own, the one `labkit fit` gives for this session.", "",
            md.table(["series", "model", "fitted params", "n", "rms residual", "residual space", "AICc",
                      "ΔAICc", "preferred", "warnings"], rows), ""]


def _video_path(source: Path, video: str) -> Path:
    vpath = Path(video) if Path(video).is_absolute() else (source.parent / video)
    return vpath if vpath.exists() else Path(video)


def _strobe_sections(source: Path, doc: dict, out: Path) -> list[str]:
    """Motion table (phi, beta, delta with their standard errors when the analysis gave them)
    and the phase figure (tilt and lateral position against phase, fitted sinusoids)."""
    from labkit.report.strobe import motion_rows, phase_figure

    lines = ["## Motion (cone angle φ, lateral amplitude β, RC offset δ = β / tan φ, Eq. 5.97)", "",
             md.table(["quantity", "value", "standard error", "unit"], motion_rows(doc)), ""]
    if doc.get("rc_offset_direction"):
        lines += [f"The rotation centre lies {doc['rc_offset_direction']} from the centroid.", ""]
    lines += ["## Tilt and lateral position against phase", ""]
    if not doc.get("phase_per_frame"):
        return lines + ["**Not drawn:** the result has no phase per frame.", ""]
    try:
        fig = phase_figure(doc, out / "fig-strobe-phase.png")
    except (LabkitError, ValueError, KeyError) as exc:
        return lines + [f"**Not drawn:** {exc}", ""]
    return lines + ["Each frame's body tilt (about the body's rest axis) and lateral position, as the "
                    "analysis measured and fitted them, against the rotation phase it gave that frame, "
                    "with the fitted sinusoids of Eq. 5.97.", "",
                    f"![tilt and lateral position against phase]({fig.name})", "",
                    f"Vector version: [{fig.stem}.svg]({fig.stem}.svg)", ""]


def _video_report(source: Path, doc: dict, out: Path) -> Path:
    _check_output_folder(source, out)
    out.mkdir(parents=True, exist_ok=True)
    strobe = "point_pattern" in doc   # labkit analyse strobe; else analyse laser
    pattern = (doc.get("point_pattern") if strobe else doc.get("pattern")) or {}
    lines = [f"# labkit report: {source.name}", "", f"Source: `{source}`  ",
             f"Generated: {_now()} by labkit {__version__}", "",
             "## Video (" + ("stroboscope" if strobe else "laser trace") + ")", ""]
    rows = [[k, doc.get(k)] for k in ("source", "frames", "fps", "apparent_hz", "phase_source") if k in doc]
    if doc.get("size"):
        rows.append(["size (px)", " x ".join(str(v) for v in doc["size"])])
    lines += [md.table(["item", "value"], rows), ""]
    if strobe:
        lines += _strobe_sections(source, doc, out)
    lines += ["## Pattern" + (" of the tracked body point" if strobe else ""), ""]
    prow = [[k.replace("_", " "), _words(v)] for k, v in pattern.items() if v is not None]
    lines += [md.table(["quantity", "value"], prow), ""]
    tilt = doc.get("tilt_rad")
    if isinstance(tilt, dict):
        lines += ["Tilt (cone) amplitudes from the trace (rad): "
                  + ", ".join(f"{k} = {md.num(v)}" for k, v in tilt.items()), ""]
    video = doc.get("source")
    if video:
        vpath = _video_path(source, video)
        try:
            frames = sample_frames(vpath)
            sheet = contact_sheet([overlay(f, pattern) for _, f in frames], [f"frame {i}" for i, _ in frames],
                                  out / "contact-sheet.png")
            lines += ["## Contact sheet", "", "Frames spread over the clip with the fitted pattern (green).",
                      "", f"![contact sheet]({sheet.name})", ""]
        except LabkitError as exc:
            lines += ["## Contact sheet", "", f"**Not drawn:** {exc}", ""]
    (out / "report.md").write_text(md.writable("\n".join(lines) + "\n"), encoding="utf-8")
    return out / "report.md"
