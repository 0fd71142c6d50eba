"""Protocol parameters from ``--set key=value``: typed by each protocol's defaults.

Values: numbers, ``true``/``false``, strings, lists ``6000,8000,12000`` and ranges
``start:stop:step`` (inclusive of ``stop`` when it falls on the grid): ``6000:20000:1000``.
Keys keep their unit suffix (``speeds_rpm``); protocols convert to SI.
"""

from __future__ import annotations

from typing import Any

from labkit.errors import LabkitError


class ParamError(LabkitError):
    """A ``--set`` value is wrong. Names the key and the problem."""


def parse_number_list(key: str, text: str) -> list[float]:
    text = text.strip()
    try:
        if ":" in text:
            parts = [float(p) for p in text.split(":")]
            if len(parts) != 3:
                raise ParamError(f"--set {key}: a range is start:stop:step, got {text!r}")
            start, stop, step = parts
            if step == 0 or (stop - start) / step < 0:
                raise ParamError(f"--set {key}: step {step:g} does not go from {start:g} to {stop:g}")
            n = int(round((stop - start) / step, 9)) + 1
            return [start + i * step for i in range(n)]
        return [float(p) for p in text.replace(";", ",").split(",") if p.strip()]
    except ValueError:
        raise ParamError(f"--set {key}: {text!r} is not a number, list (a,b,c) or range (a:b:step)") from None


def coerce(key: str, text: str, default: Any) -> Any:
    """Convert ``text`` to the type of ``default``."""
    if isinstance(default, bool):
        low = text.strip().lower()
        if low in ("1", "true", "yes", "on"):
            return True
        if low in ("0", "false", "no", "off"):
            return False
        raise ParamError(f"--set {key}: {text!r} is not true/false")
    if isinstance(default, int):
        try:
            return int(text)
        except ValueError:
            raise ParamError(f"--set {key}: {text!r} is not an integer") from None
    if isinstance(default, float):
        try:
            return float(text)
        except ValueError:
            raise ParamError(f"--set {key}: {text!r} is not a number") from None
    if isinstance(default, list):
        return parse_number_list(key, text)
    return text


def resolve_params(defaults: dict[str, Any], overrides: dict[str, Any] | list[str] | None,
                   protocol: str = "") -> dict[str, Any]:
    """Defaults updated by overrides (``["k=v", ...]`` or a dict). Unknown keys are errors."""
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
            raise ParamError(f"--set {key}: unknown parameter of {name} (known: {known})")
        params[key] = coerce(key, value, defaults[key]) if isinstance(value, str) else value
    return params
