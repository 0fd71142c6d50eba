"""What a run declares about its data, as the sinks read it: the columns of a result row
(:class:`Column`) and how rows are drawn and fitted (:class:`Hints`, bluesky's start-document
``hints``; ADR 0021).

A protocol declares them (:class:`labkit.protocols.ProtocolDef` ``row`` and ``hints``; the
built-ins in :mod:`labkit.protocols.paper_figures`), the run's start document
(:class:`labkit.documents.RunStart`) carries them as JSON, and the rerun sink
(:mod:`labkit.stream.run`) and the report (:mod:`labkit.report.plans`) read only that: a
protocol from a plugin gets a live figure, a live fit and a report figure without a line of
labkit changed. Sessions recorded before the start document carried hints get them from
:mod:`labkit.protocols.legacy_hints`, the one place protocols are known by name.

Pure data below the sinks and the protocols: this module imports only :mod:`labkit.units` and
:mod:`labkit.errors`.
"""

from __future__ import annotations

import math
import re
from dataclasses import asdict, dataclass, field
from typing import Any

from labkit.errors import LabkitError
from labkit.units import RAD_S_PER_RPM

#: residual styles of a figure: label template (``{y_unit}``) and the name used in docs
RESIDUALS: dict[str, str] = {"ratio": "residual [%] (data / fit - 1)",
                             "difference": "residual [{y_unit}] (data - fit)"}
#: models a reference curve may have (the curve is evaluated here, without the fit package)
CURVE_MODELS = ("power-law", "spin-critical")
#: the x units a step's speed target (rad/s) can be drawn in, with the factor from rad/s
TARGET_UNITS: dict[str, float] = {"rad/s": 1.0, "RPM": 1.0 / RAD_S_PER_RPM}


class HintsError(LabkitError, ValueError):
    """A declaration that cannot be drawn (an unknown residual style, a curve model...)."""


@dataclass(frozen=True)
class Column:
    """One key of a result row, its unit (``""`` for a count or a word) and what it is.

    ``analysis``: the value comes out of an image analysis (OpenCV, least squares) whose last
    digits depend on the CPU's floating-point path (SIMD kernels, BLAS), so a replay compares it
    within a relative 1e-6 instead of exactly (:func:`analysis_keys`).

    ``accuracy``: the quantity of the protocol's image analysis (``ProtocolDef.image_analysis``,
    e.g. ``tilt`` of the laser analysis) whose stated accuracy holds this value when a replay
    compares it with a session made by another version of the analysis; ``accuracy_of``: the
    key of the same row that accuracy is a share of (a standard error against its angle)."""

    name: str
    unit: str = ""
    doc: str = ""
    analysis: bool = False
    accuracy: str = ""
    accuracy_of: str = ""


def analysis_keys(row: tuple[Column, ...]) -> frozenset[str]:
    """The keys of a row whose values a replay compares within tolerance (``Column.analysis``)."""
    return frozenset(c.name for c in row if c.analysis)


@dataclass(frozen=True)
class Curve:
    """A reference curve drawn with the data, e.g. the paper's ``y = 224e6 x^-1.9``."""

    name: str            # "paper"
    formula: str         # "y = 224e6 x^-1.9"
    model: str           # one of CURVE_MODELS
    params: dict[str, float]
    figure: str = ""     # "Fig. 5.25": the report's legend says where the curve is from

    def __post_init__(self) -> None:
        if self.model not in CURVE_MODELS:
            raise HintsError(f"reference curve {self.name!r}: model {self.model!r} is not one of "
                             f"{', '.join(CURVE_MODELS)}")

    @property
    def live_label(self) -> str:
        return f"{self.name}: {self.formula}"

    @property
    def report_label(self) -> str:
        return f"{self.name} {self.figure}: {self.formula}" if self.figure else self.live_label

    def at(self, x: Any) -> Any:
        """The curve at ``x`` (a number or a numpy array): ``a x^b`` for the power law; for
        ``spin-critical`` the spin at the drop from Eq. 6.37, ``-k w^2 = C (1 - w/w_c)`` with
        ``k = v/w - 1``, i.e. ``v = w - C/w + C/w_c`` (params ``C``, ``omega_c``)."""
        if self.model == "spin-critical":
            c, w_c = self.params["C"], self.params["omega_c"]
            return x - c / x + c / w_c
        return self.params["a"] * x ** self.params["b"]


@dataclass(frozen=True)
class ReportFit:
    """One fit the report makes (``labkit fit`` model and options, as plain data).

    ``omega_c``: a number, ``"fit"``, ``"inf"`` or None (the model's default); ``inertia``:
    the fit needs the floator's inertia from the rig file; ``reference``: the hints' reference
    curve is drawn on this fit's figure; ``x``/``y``: columns (None: the model's defaults)."""

    slug: str
    title: str
    model: str
    figure_title: str = ""
    fixed: dict[str, float] = field(default_factory=dict)
    omega_c: float | str | None = None
    inertia: bool = False
    reference: bool = False
    x: str | None = None
    y: str | None = None


@dataclass(frozen=True)
class Series:
    """One more quantity of the row drawn against the figure's x, in its own panel beneath it
    (no fit): ``y`` the column, ``name`` and ``unit`` its axis label (``beta [mm]``)."""

    y: str
    name: str
    unit: str = ""

    @property
    def label(self) -> str:
        return f"{self.name} [{self.unit}]" if self.unit else self.name


@dataclass(frozen=True)
class Hints:
    """How a protocol's rows are drawn and fitted: the figure is ``y`` against ``x`` (row
    columns), named ``<name> [<unit>]``; ``fit`` is the ``labkit fit`` model the live view
    redraws at every point ("" for none); ``report_fits`` the report's fits (empty: ``fit``
    alone); ``residual`` ``ratio`` or ``difference``; ``root`` the rerun entity of the figure
    (derived from ``figure`` when empty); ``also`` more columns drawn against the same x, each
    in its own panel (:class:`Series`; the strobe sweep's beta and delta beside phi)."""

    x: str
    y: str
    x_name: str
    x_unit: str
    y_name: str
    y_unit: str
    figure: str = ""
    title: str = ""
    root: str = ""
    fit: str = ""
    residual: str = "difference"
    legend_corner: str = "RightTop"
    reference: Curve | None = None
    report_fits: tuple[ReportFit, ...] = ()
    report_title: str = ""
    notes: tuple[str, ...] = ()
    also: tuple[Series, ...] = ()

    def __post_init__(self) -> None:
        if self.residual not in RESIDUALS:
            raise HintsError(f"hints: residual {self.residual!r} is not one of {', '.join(RESIDUALS)}")

    @property
    def x_label(self) -> str:
        """``rotor speed [RPM]``: the x axis, and the rerun timeline the figure is drawn on."""
        return f"{self.x_name} [{self.x_unit}]"

    @property
    def y_label(self) -> str:
        return f"{self.y_name} [{self.y_unit}]"

    @property
    def figure_title(self) -> str:
        """``Fig. 5.25: force [g] against rotor speed [RPM]`` (the live figure's title)."""
        body = self.title or f"{self.y_label} against {self.x_label}"
        return f"{self.figure}: {body}" if self.figure else body

    @property
    def residual_label(self) -> str:
        return RESIDUALS[self.residual].format(y_unit=self.y_unit)

    @property
    def entity_root(self) -> str:
        """``/fig5_25``: the rerun entity the figure's data, fit and residuals sit under."""
        if self.root:
            return self.root
        slug = re.sub(r"[^0-9a-z]+", "_", (self.figure or f"{self.y}_vs_{self.x}").lower()).strip("_")
        return f"/{slug}"

    def step_x(self, target_rad_s: float) -> float | None:
        """A step's speed target on the x axis, when x is a speed (None otherwise)."""
        factor = TARGET_UNITS.get(self.x_unit)
        return None if factor is None else target_rad_s * factor

    def point_xy(self, point: dict[str, Any], y_key: str | None = None) -> tuple[float, float] | None:
        """``(x, y)`` of a result row (``y_key``: another column than ``y``), None when either is
        missing or not a finite number."""
        x, y = point.get(self.x), point.get(y_key or self.y)
        if not isinstance(x, int | float) or not isinstance(y, int | float):
            return None
        if not (math.isfinite(x) and math.isfinite(y)):
            return None
        return float(x), float(y)

    def fits_for_report(self) -> tuple[ReportFit, ...]:
        """``report_fits``, or the live ``fit`` alone (x and y as declared) when none is given."""
        if self.report_fits or not self.fit:
            return self.report_fits
        return (ReportFit(self.fit, f"{self.fit} fit: {self.y_label} against {self.x_label}", self.fit,
                          self.report_title or self.figure_title, reference=self.reference is not None,
                          x=self.x, y=self.y),)

    def to_json(self) -> dict[str, Any]:
        out = asdict(self)
        out["report_fits"] = [asdict(f) for f in self.report_fits]
        out["notes"] = list(self.notes)
        out["also"] = [asdict(s) for s in self.also]
        return out

    @classmethod
    def from_json(cls, obj: dict[str, Any]) -> Hints:
        """The hints of a start document (inverse of :meth:`to_json`); HintsError naming the
        key when something is missing or of the wrong kind."""
        try:
            data = dict(obj)
            curve = data.get("reference")
            data["reference"] = Curve(**curve) if curve else None
            data["report_fits"] = tuple(ReportFit(**f) for f in data.get("report_fits") or ())
            data["notes"] = tuple(data.get("notes") or ())
            data["also"] = tuple(Series(**s) for s in data.get("also") or ())
            return cls(**data)
        except (TypeError, KeyError) as exc:
            raise HintsError(f"start document hints cannot be read: {exc}") from None
