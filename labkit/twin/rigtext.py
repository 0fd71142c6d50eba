"""A twin rig file: the shipped emulated rig's devices, with the user's magnets and geometry.

The emulated devices (motor, tachometers, balance on ``plant=model-*``), limits and speed
loop come from the bundled ``emulated-fig525`` / ``emulated-fig618`` rigs; ``[bodies.*]`` and
``[geometry]`` come from the user's rig file, so the model plant is built from its magnets.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

from labkit.rig import bundled_rig_path
from labkit.rig.checks import read_rig_text


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (str, list)):
        # a JSON string or list is a TOML value once non-BMP characters stay raw (JSON would write
        # surrogate pairs) and DEL is escaped (TOML allows no raw control characters)
        return json.dumps(v, ensure_ascii=False).replace("\x7f", "\\u007f")
    return repr(v)


def _table(name: str, table: dict[str, Any]) -> str:
    return f"[{name}]\n" + "".join(f"{k} = {_value(v)}\n" for k, v in table.items())


def _strip_sections(text: str, prefixes: tuple[str, ...]) -> str:
    """``text`` without the TOML sections whose header starts with one of ``prefixes``."""
    out, skipping = [], False
    for line in text.splitlines(keepends=True):
        stripped = line.strip()
        if stripped.startswith("["):
            skipping = stripped.strip("[]").startswith(prefixes)
        if not skipping:
            out.append(line)
    return "".join(out)


def twin_rig_text(user_rig: Path, setup: str) -> str:
    """The twin rig for ``setup`` (``fig525``, ``fig618`` or ``camera``: the Fig. 5.25 rig plus
    the emulated camera) with ``user_rig``'s magnets."""
    base = read_rig_text(bundled_rig_path(f"emulated-{setup}"))  # type: ignore[arg-type]
    user = tomllib.loads(read_rig_text(user_rig))
    text = _strip_sections(base, ("bodies", "geometry"))
    extra = [_table(f"bodies.{n}", t) for n, t in (user.get("bodies") or {}).items()]
    geometry = dict(user.get("geometry") or {})
    geometry["balance_under"] = "rotator"   # the twin's set-ups weigh the rotator
    extra.append(_table("geometry", geometry))
    return text.rstrip() + "\n\n" + "\n".join(extra)


def write_twin_rig(user_rig: Path, setup: str, folder: Path) -> Path:
    """Write :func:`twin_rig_text` to ``folder/twin-<setup>.toml`` and return its path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"twin-{setup}.toml"
    path.write_text(twin_rig_text(user_rig, setup))
    return path
