"""Pages of the docs that run: each ```python block of a page, in order, in one namespace, must
print what the ```text block after it shows (words exactly, numbers to a relative 1e-2, since
fits and video analysis differ in their last digits between machines)."""

from __future__ import annotations

import math
import re
from pathlib import Path

BLOCK = re.compile(r"```(python|text)\n(.*?)```", re.S)
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def page_cells(page: Path) -> list[tuple[str, str | None]]:
    """``(code, expected output or None)`` for every python block of ``page``."""
    out: list[tuple[str, str | None]] = []
    for kind, body in BLOCK.findall(page.read_text(encoding="utf-8")):
        if kind == "python":
            out.append((body, None))
        elif out and out[-1][1] is None:
            out[-1] = (out[-1][0], body)
    return out


def same_output(got: str, expected: str) -> bool:
    """Equal text apart from numbers, which agree to a relative 1e-2 (absolute 1e-3)."""
    if NUMBER.sub("#", got).split() != NUMBER.sub("#", expected).split():
        return False
    pairs = zip(NUMBER.findall(got), NUMBER.findall(expected), strict=True)
    return all(math.isclose(float(a), float(b), rel_tol=1e-2, abs_tol=1e-3) for a, b in pairs)


def run_page(page: Path, name: str) -> None:
    """Run every python block of ``page`` in order in one namespace (``__name__`` = ``name``);
    AssertionError naming the block when what it prints differs from the page."""
    import contextlib
    import io

    namespace: dict = {"__name__": name}
    for number, (code, expected) in enumerate(page_cells(page), 1):
        buffer = io.StringIO()
        with contextlib.redirect_stdout(buffer):
            exec(compile(code, f"{page.name} block {number}", "exec"), namespace)  # noqa: S102
        if not same_output(buffer.getvalue(), expected or ""):
            raise AssertionError(f"{page.name} block {number} printed:\n{buffer.getvalue()}\n"
                                 f"the page shows:\n{expected}")
