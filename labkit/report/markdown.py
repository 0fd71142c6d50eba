"""Small markdown helpers for reports (tables, numbers, parameter tables)."""

from __future__ import annotations

import math
import re

from labkit.fit.result import FitResult

_SURROGATE = re.compile("[\ud800-\udfff]")


def _escaped(match: re.Match[str]) -> str:
    code = ord(match[0])
    return f"\\x{code - 0xDC00:02x}" if 0xDC80 <= code <= 0xDCFF else f"\\u{code:04x}"


def writable(text: str) -> str:
    """``text`` with every lone surrogate written out: ``\\xe9`` for a byte that was not UTF-8
    (Python's surrogateescape of a Latin-1 ``--notes`` or folder name), ``\\ud800`` for another
    (a JSON ``\\ud800`` escape); a report in UTF-8 cannot hold them as they are."""
    return _SURROGATE.sub(_escaped, text)


def num(v, digits: int = 5) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            return "inf" if v > 0 else ("-inf" if v < 0 else "")
        return f"{v:.{digits}g}"
    return str(v).replace("|", "\\|").replace("\n", " ")


def table(headers: list[str], rows: list[list]) -> str:
    out = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    out += ["| " + " | ".join(num(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def param_table(res: FitResult) -> str:
    rows = []
    for k, p in res.params.items():
        if p.fixed:
            rows.append([k, p.value, "fixed", "", p.unit])
            continue
        ci = f"[{num(p.ci95[0])}, {num(p.ci95[1])}]"
        if p.bootstrap_ci95 is not None:
            ci += f" (bootstrap [{num(p.bootstrap_ci95[0])}, {num(p.bootstrap_ci95[1])}])"
        rows.append([k + (" (derived)" if p.derived else ""), p.value, num(p.stderr, 3), ci, p.unit])
    return table(["parameter", "value", "stderr", "95 % interval", "unit"], rows)


def quality_line(res: FitResult) -> str:
    return (f"n = {res.n}, dof = {res.dof}, rms residual = {num(res.rms_residual, 4)} "
            f"({res.residual_space}), R² = {num(res.r_squared, 5)}, AIC = {num(res.aic, 4)}")
