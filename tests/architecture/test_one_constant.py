"""Standard gravity is defined once, in ``labkit/units.py`` (``G0``): no other module assigns a
``G0`` or writes 9.80665 (or 9.81) as a number (issue 24)."""

from __future__ import annotations

import ast
from pathlib import Path

LABKIT = Path(__file__).resolve().parents[2] / "labkit"
GRAVITY = (9.80665, 9.81)


def gravity_definitions(source: str) -> list[int]:
    """Lines that assign a name ``G0`` or hold standard gravity as a numeric literal."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Constant) and isinstance(node.value, float) and node.value in GRAVITY:
            lines.append(node.lineno)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == "G0" for t in targets):
                lines.append(node.lineno)
    return sorted(set(lines))


def test_g0_is_defined_once():
    found = [f"{path.relative_to(LABKIT.parent)}:{line}" for path in sorted(LABKIT.rglob("*.py"))
             if path != LABKIT / "units.py"
             for line in gravity_definitions(path.read_text(encoding="utf-8"))]
    assert not found, f"standard gravity defined outside labkit/units.py (import G0): {found}"
    assert gravity_definitions((LABKIT / "units.py").read_text(encoding="utf-8"))


def test_the_checker_sees_definitions_and_literals():
    assert gravity_definitions("G0 = 9.80665\n") == [1]
    assert gravity_definitions("x = 1e-3 * 9.80665 * w\ny: float = 9.81\n") == [1, 2]
    assert gravity_definitions('"""g0 = 9.80665 in a docstring"""\nfrom labkit.units import G0\n') == []
