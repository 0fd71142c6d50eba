"""Fit a loaded table with a named model, series by series: what ``labkit fit`` runs.

``fit_table(table, "spin-critical", FitOptions(omega_c=3000))`` returns a :class:`FitReport`
whose ``to_json()`` is ``{"model", "series": {NAME: {"params": {P: {"value", "stderr",
"ci95"}}, "n", "rms_residual", "warnings", ...}}}``; a table without a series column gives
the single series ``all``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from labkit.errors import DataFileError, FitError
from labkit.fit.bootstrap import bootstrap
from labkit.fit.data import Table, to_si
from labkit.fit.models import (
    MODELS,
    PAPER_OMEGA_C,
    fit_cone_angle,
    fit_mbs_distance,
    fit_mbs_force,
    fit_mbs_parts,
    fit_pfr_force,
    fit_power_law,
    fit_spin_critical,
)
from labkit.fit.result import FitResult


@dataclass(frozen=True)
class FitOptions:
    """Options of a table fit. ``x``/``y``/``sigma``/``series`` override the default columns;
    ``inertia`` (kg m^2) for pfr-force and cone-angle; ``omega_c`` (rad/s, ``math.inf`` or
    ``"fit"``) for spin-critical; ``fixed`` parameter values; ``bootstrap`` resamples (0 = off);
    ``on_progress(done, total)`` is called after each bootstrap resample."""

    x: str | None = None
    y: str | None = None
    sigma: str | None = None
    series: str | None = None
    inertia: float | None = None
    omega_c: float | str = PAPER_OMEGA_C
    fixed: dict[str, float] = field(default_factory=dict)
    bootstrap: int = 0
    seed: int = 0
    on_progress: Callable[[int, int], None] | None = field(default=None, compare=False)


@dataclass(frozen=True)
class FitReport:
    """All series of one model fitted to one source."""

    model: str
    source: str
    series: dict[str, FitResult]
    columns: dict[str, str]

    def to_json(self) -> dict:
        return {"model": self.model, "source": self.source, "columns": self.columns,
                "series": {k: r.to_json() for k, r in self.series.items()}}


def fit_table(table: Table, model: str, options: FitOptions | None = None) -> FitReport:
    """Fit every series of ``table`` with ``model`` (a key of :data:`labkit.fit.models.MODELS`)."""
    options = options or FitOptions()
    if model not in MODELS:
        raise FitError(f"unknown model {model!r}; choose one of {', '.join(MODELS)}")
    spec = MODELS[model]
    x_col = _pick(table, options.x, spec.x, "x", model)
    y_col = _pick(table, options.y, spec.y, "y", model)
    sigma_col = options.sigma or _default_sigma(table, y_col)
    if sigma_col is not None and sigma_col not in table.numeric:
        raise DataFileError(table.source, sigma_col,
                            f"no such numeric column; columns: {', '.join(table.names)}")
    extras = {role: next((c for c in cands if c in table.numeric), None) for role, cands in spec.extra}
    series_col = options.series or ("series" if "series" in table.text or "series" in table.numeric else None)
    if series_col is not None and series_col not in table.text and series_col not in table.numeric:
        raise DataFileError(table.source, series_col, "no such column for --series")
    columns = {"x": x_col, "y": y_col}
    if sigma_col:
        columns["sigma"] = sigma_col
    columns.update({k: v for k, v in extras.items() if v})
    table, skipped = _drop_empty_rows(table, [x_col, y_col])
    table, inconsistent = _drop_inconsistent_rows(table)
    results: dict[str, FitResult] = {}
    for name, part in _split(table, series_col):
        if model == "mbs-force" and extras.get("repulsive") and extras.get("attractive"):
            parts = _fit_parts(part, x_col, extras)
            results.update(parts if name == "all" else {f"{name}/{k}": v for k, v in parts.items()})
            continue
        try:
            results[name] = _fit_one(part, spec.si, model, x_col, y_col, sigma_col, extras, options)
        except FitError as exc:
            raise FitError(f"{exc} [series {name!r} of {table.source}]" if name != "all"
                           else f"{exc} [{table.source}]") from None
    if skipped:
        note = (f"{skipped} row(s) without any {x_col} or {y_col} value skipped "
                "(steps that produced no measurement)")
        results = {k: replace(r, warnings=(*r.warnings, note)) for k, r in results.items()}
    if inconsistent:
        note = (f"left out of the fit: {inconsistent}, whose trials did not agree within the protocol's "
                "consistency_pct (column 'consistent' false)")
        results = {k: replace(r, warnings=(*r.warnings, note)) for k, r in results.items()}
    return FitReport(model, table.source, results, columns)


def _drop_inconsistent_rows(table: Table) -> tuple[Table, str]:
    """Rows a protocol marked ``consistent: false`` (a spin-critical step whose repeated trials
    did not agree) are left out of the fit; returns the table and the steps left out, in words
    ("" when none). Kept in, one such step carried the largest residual of a whole series."""
    flags = table.text.get("consistent")
    if flags is None and "consistent" in table.numeric:
        flags = ["False" if v == 0 else "True" for v in table.numeric["consistent"]]
    if flags is None:
        return table, ""
    bad = np.array([f.strip().lower() in ("false", "0") for f in flags])
    if not bad.any() or bad.all():
        return table, ""  # every step inconsistent: fitted, each point says so in the table
    steps = table.numeric.get("step")
    names = [f"step {int(s)}" if steps is not None and np.isfinite(s) else f"row {i + 1}"
             for i, s in enumerate(steps if steps is not None else [math.nan] * len(bad)) if bad[i]]
    return table.subset(~bad), ", ".join(names)


def _drop_empty_rows(table: Table, cols: list[str]) -> tuple[Table, int]:
    """Rows where every one of ``cols`` is missing are steps without a measurement (e.g. a
    spin-critical step where the floator never dropped): skip them. A row with only some
    values missing stays, so the fit refuses it and names it."""
    empty = np.all([~np.isfinite(table.numeric[c]) for c in cols], axis=0)
    if not empty.any():
        return table, 0
    return table.subset(~empty), int(empty.sum())


def _fit_one(table: Table, si: bool, model: str, x_col: str, y_col: str, sigma_col: str | None,
             extras: dict, options: FitOptions) -> FitResult:
    cols = {"x": (x_col, table.numeric[x_col]), "y": (y_col, table.numeric[y_col])}
    if sigma_col:
        cols["sigma"] = (sigma_col, table.numeric[sigma_col])
    for role, name in extras.items():
        if name:
            cols[role] = (name, table.numeric[name])
    if si:
        cols = {role: to_si(name, values) for role, (name, values) in cols.items()}
    data = {role: values for role, (_, values) in cols.items()}
    names = {role: name for role, (name, _) in cols.items()}

    def run(d: dict[str, np.ndarray]) -> FitResult:
        return _dispatch(model, d, names, options)

    result = run(data)
    if options.bootstrap:
        result = bootstrap(run, data, result, n=options.bootstrap, seed=options.seed,
                           on_progress=options.on_progress)
    return result


def _dispatch(model: str, d: dict, names: dict, options: FitOptions) -> FitResult:
    xy = {"x_name": names["x"], "y_name": names["y"]}
    sigma = d.get("sigma")
    fixed = options.fixed
    _only_fix(model, fixed, {"pfr-force": {"tau_S"}, "cone-angle": {"tau_S"},
                             "mbs-force": {"a", "b", "c", "d"}}.get(model, set()))
    if model == "power-law":
        return fit_power_law(d["x"], d["y"], sigma=sigma, **xy)
    if model == "pfr-force":
        return fit_pfr_force(d["x"], d["y"], sigma=sigma, inertia=options.inertia,
                             tau_S=fixed.get("tau_S"), **xy)
    if model == "spin-critical":
        return fit_spin_critical(d["x"], d["y"], omega_c=options.omega_c, sigma=sigma, **xy)
    if model == "cone-angle":
        return fit_cone_angle(d["x"], d["y"], inertia=options.inertia, spin=d.get("spin"), sigma=sigma,
                              tau_S=fixed.get("tau_S"), **xy)
    if model == "mbs-force":
        return fit_mbs_force(d["x"], d["y"], sigma=sigma, fixed=fixed, **xy)
    if model == "mbs-distance":
        return fit_mbs_distance(d["x"], d["y"], sigma=sigma, **xy)
    raise FitError(f"unknown model {model!r}")


def _only_fix(model: str, fixed: dict, allowed: set[str]) -> None:
    bad = set(fixed) - allowed
    if bad:
        can = f"only {', '.join(sorted(allowed))}" if allowed else "none"
        raise FitError(f"{model}: cannot fix {', '.join(sorted(bad))} ({can} can be fixed)")


def _fit_parts(table: Table, x_col: str, extras: dict) -> dict[str, FitResult]:
    _, r = to_si(x_col, table.numeric[x_col])
    _, rep = to_si(extras["repulsive"], table.numeric[extras["repulsive"]])
    _, att = to_si(extras["attractive"], table.numeric[extras["attractive"]])
    return fit_mbs_parts(r, rep, att, x_name=to_si(x_col, r)[0])


def _pick(table: Table, given: str | None, candidates: tuple[str, ...], role: str, model: str) -> str:
    if given is not None:
        if given not in table.numeric:
            raise DataFileError(table.source, given, f"no numeric column {given!r} for --{role}; "
                                f"columns: {', '.join(table.names) or '(none)'}")
        return given
    for c in candidates:
        if c in table.numeric:
            return c
    raise DataFileError(table.source, "", f"{model} needs a {role} column ({' or '.join(candidates)}); "
                        f"columns here: {', '.join(table.names) or '(none)'}; choose one with --{role}")


def _default_sigma(table: Table, y_col: str) -> str | None:
    stem, _, unit = y_col.rpartition("_")
    for c in (f"{y_col}_stderr", f"{stem}_stderr_{unit}", f"{y_col}_err"):
        if c in table.numeric and np.all(np.isfinite(table.numeric[c])) and np.all(table.numeric[c] > 0):
            return c
    return None


def _split(table: Table, series_col: str | None):
    if series_col is None:
        yield "all", table
        return
    values = table.text.get(series_col)
    if values is None:
        values = [_fmt(v) for v in table.numeric[series_col]]
    seen: list[str] = []
    for v in values:
        if v not in seen:
            seen.append(v)
    arr = np.array(values, dtype=object)
    for v in seen:
        yield (v or "all"), table.subset(arr == v)


def _fmt(v: float) -> str:
    return str(int(v)) if math.isfinite(v) and v == int(v) else str(v)
