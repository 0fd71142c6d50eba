"""Protocol parameters from ``--set key=value``: typed by each protocol's defaults.

Values: numbers, ``true``/``false``, strings, lists ``6000,8000,12000`` and ranges
``start:stop:step`` (inclusive of ``stop`` when it falls on the grid): ``6000:20000:1000``.
Keys keep their unit suffix (``speeds_rpm``); protocols convert to SI.

Every number must be finite (``nan``/``inf`` are refused); a speed (``*_rpm``) is at most
:data:`MAX_SPEED_RPM`, a time (``*_s``) between 0 and :data:`MAX_DURATION_S`, and a list or
range at most :data:`MAX_LIST_VALUES` values (the count is computed before any list is
built). Limits are documented in docs/reference/protocols.md.
"""

from __future__ import annotations

import difflib
import math
from typing import Any

from labkit.errors import LabkitError
from labkit.ranges import RangeError, parse_range
from labkit.rig import MAX_DURATION_S, MAX_SPEED_RPM
from labkit.units import RAD_S_PER_RPM

#: The most values a ``--set`` list or range may give, and the most steps a plan may have.
MAX_LIST_VALUES = 10_000
MAX_PLAN_STEPS = 10_000
#: The longest ``--set`` value text (a 5 MB argument is not a parameter).
MAX_VALUE_CHARS = 100_000


class ParamError(LabkitError):
    """A ``--set`` value is wrong. Names the key and the problem."""


def _short(text: str, limit: int = 40) -> str:
    return repr(text) if len(text) <= limit else repr(text[:limit]) + f"... ({len(text)} characters)"


def check_length(key: str, text: str) -> None:
    if len(text) > MAX_VALUE_CHARS:
        raise ParamError(f"--set {key}: {len(text)} characters is too long (limit {MAX_VALUE_CHARS})")


def check_value(key: str, value: float) -> float:
    """``value`` of ``--set key`` if finite and within the caps of its unit suffix."""
    if not math.isfinite(value):
        raise ParamError(f"--set {key}: must be a finite number, got {value!r}")
    if key.endswith("_rpm") and abs(value) > MAX_SPEED_RPM:
        raise ParamError(f"--set {key}: {value:g} is beyond the sanity cap of {MAX_SPEED_RPM:.0f} RPM")
    if key.endswith("_rad_s"):
        if abs(value) > MAX_SPEED_RPM * RAD_S_PER_RPM:
            raise ParamError(f"--set {key}: {value:g} rad/s is beyond the cap of {MAX_SPEED_RPM:.0f} RPM")
    elif key.endswith("_s") and not 0 <= value <= MAX_DURATION_S:
        raise ParamError(f"--set {key}: must be in [0, {MAX_DURATION_S:.0f}] s, got {value:g}")
    return value


def check_count(key: str, n: float, what: str = "values", limit: int = MAX_LIST_VALUES) -> None:
    """Refuse ``n`` (computed before anything is built) above ``limit``."""
    if n > limit:
        raise ParamError(f"--set {key}: gives {n:.0f} {what}, more than the limit of {limit}")


def parse_number_list(key: str, text: str) -> list[float]:
    """One list, range or number in the grammar of :mod:`labkit.ranges` (``a:b:step=S``,
    ``a:b:n=N``, ``a,b,c``; the old ``a:b:S`` is the step), every value checked."""
    text = text.strip()
    check_length(key, text)
    try:
        values = parse_range(text, bare="step", limit=MAX_LIST_VALUES)
    except RangeError as exc:
        raise ParamError(f"--set {key}: {exc} (a number, list a,b,c or range "
                         "a:b:step=S / a:b:n=N)") from None
    return [check_value(key, v) for v in values]


def coerce(key: str, text: str, default: Any) -> Any:
    """Convert ``text`` to the type of ``default``."""
    if isinstance(default, bool):
        low = text.strip().lower()
        if low in ("1", "true", "yes", "on"):
            return True
        if low in ("0", "false", "no", "off"):
            return False
        raise ParamError(f"--set {key}: {text!r} is not true/false")
    check_length(key, text)
    if isinstance(default, int):
        try:
            value = int(text)
        except ValueError:
            raise ParamError(f"--set {key}: {_short(text)} is not an integer") from None
        if abs(value) > MAX_PLAN_STEPS and not key.endswith(("_rpm", "_s", "_g")):
            raise ParamError(f"--set {key}: {value} is beyond the limit of {MAX_PLAN_STEPS}")
        return int(check_value(key, value))
    if isinstance(default, float):
        try:
            return check_value(key, float(text))
        except ValueError:
            raise ParamError(f"--set {key}: {_short(text)} is not a number") from None
    if isinstance(default, list):
        return parse_number_list(key, text)
    return text


def resolve_params(defaults: dict[str, Any], overrides: dict[str, Any] | list[str] | None,
                   protocol: str = "", bounds: dict[str, tuple[float | None, float | None]] | None = None
                   ) -> dict[str, Any]:
    """Defaults updated by overrides (``["k=v", ...]`` or a dict). Unknown keys are errors, and
    so is a value outside the protocol's declared ``bounds`` (``ProtocolDef.bounds``)."""
    params = {k: (list(v) if isinstance(v, list) else v) for k, v in defaults.items()}
    if overrides is None:
        return params
    items: list[tuple[str, Any]]
    if isinstance(overrides, dict):
        items = list(overrides.items())
    else:
        items = []
        for text in overrides:
            key, sep, value = text.partition("=")
            if not sep:
                raise ParamError(f"--set {text!r}: expected key=value")
            items.append((key.strip(), value))
    for key, value in items:
        if key not in defaults:
            known = ", ".join(sorted(defaults))
            name = protocol or "this protocol"
            close = difflib.get_close_matches(key, sorted(defaults), n=1, cutoff=0.6)
            guess = f"; did you mean {close[0]!r}?" if close else ""
            raise ParamError(f"--set {key}: unknown parameter of {name}{guess} (known: {known})")
        default = defaults[key]
        typed = isinstance(value, str)
        params[key] = coerce(key, value, default) if typed else check_typed(key, value, default)
        if key in (bounds or {}):
            check_bounds(key, params[key], *(bounds or {})[key])
    return params


def check_bounds(key: str, value: Any, low: float | None, high: float | None) -> None:
    """Refuse a number (or any number of a list) outside ``[low, high]`` (None: no bound)."""
    from labkit.protocols.declaration import unit_of

    for v in value if isinstance(value, list) else [value]:
        if not _is_number(v):
            continue
        if (low is not None and v < low) or (high is not None and v > high):
            unit = f" {unit_of(key)}" if unit_of(key) else ""
            lo = "-inf" if low is None else f"{low:g}"
            hi = "inf" if high is None else f"{high:g}"
            raise ParamError(f"--set {key}: {v:g}{unit} is outside the protocol's bounds [{lo}, {hi}]{unit}")


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def check_typed(key: str, value: Any, default: Any) -> Any:
    """A value given already typed (a session's run.json on --resume) has the type of the
    default and obeys the same rules as one typed after ``--set``."""
    if isinstance(default, bool) or isinstance(default, str):
        if type(value) is not type(default):
            raise ParamError(f"--set {key}: must be {type(default).__name__}, got {value!r:.40}")
        return value
    if isinstance(default, int | float):
        if not _is_number(value) or (isinstance(default, int) and not isinstance(value, int)):
            raise ParamError(f"--set {key}: must be a number, got {value!r:.40}")
        return type(default)(check_value(key, value))
    if isinstance(default, list):
        if not isinstance(value, list) or not all(_is_number(v) for v in value):
            raise ParamError(f"--set {key}: must be a list of numbers, got {value!r:.40}")
        check_count(key, len(value))
        return [check_value(key, float(v)) for v in value]
    return value
