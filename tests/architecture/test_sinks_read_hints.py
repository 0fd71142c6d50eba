"""The live view and the report know protocols only through their hints (ADR 0021): no code in
``labkit/stream`` or ``labkit/report`` compares a protocol name or looks a table up by one.
Read from the source with ``ast``; sessions without hints get theirs from
``labkit/protocols/legacy_hints.py``, the one place protocols are known by name."""

from __future__ import annotations

import ast
from pathlib import Path

from labkit.protocols import PROTOCOLS

LABKIT = Path(__file__).resolve().parents[2] / "labkit"
SINKS = ("stream", "report")


def _is_protocol_name(node: ast.AST) -> bool:
    """A protocol name: a built-in one as a string, or a variable/attribute called ``protocol``."""
    if isinstance(node, ast.Constant):
        return isinstance(node.value, str) and node.value in PROTOCOLS
    if isinstance(node, ast.Name):
        return node.id == "protocol"
    return isinstance(node, ast.Attribute) and node.attr == "protocol"


def protocol_name_uses(source: str) -> list[int]:
    """Lines where a protocol name is compared, used as a key, or matched."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        operands: list[ast.AST] = []
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
        elif isinstance(node, ast.Subscript):
            operands = [node.slice]
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get":
            operands = node.args[:1]
        elif isinstance(node, ast.Match):
            operands = [node.subject]
        if any(_is_protocol_name(o) for o in operands):
            lines.append(node.lineno)
    return lines


def test_no_sink_compares_a_protocol_name():
    found = {f"{path.relative_to(LABKIT.parent)}:{line}"
             for part in SINKS for path in sorted((LABKIT / part).rglob("*.py"))
             for line in protocol_name_uses(path.read_text(encoding="utf-8"))}
    assert not found, f"protocol names used in sinks (read the run's hints instead): {sorted(found)}"


def labkit_imports(source: str) -> set[str]:
    """The ``labkit...`` modules a source imports (at module level or inside functions)."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            out.add(node.module)
    return {m for m in out if m.startswith("labkit.")}


def test_the_live_view_reads_hints_without_importing_the_protocols():
    """``labkit.stream`` sits below ``labkit.protocols`` (docs: layer order io < devices <
    documents < session|stream < control < protocols < cli): it knows ``labkit.hints`` only."""
    found = {f"{path.relative_to(LABKIT.parent)}: {m}" for path in sorted((LABKIT / "stream").rglob("*.py"))
             for m in labkit_imports(path.read_text(encoding="utf-8")) if m.startswith("labkit.protocols")}
    assert not found, sorted(found)
    assert "labkit.hints" in labkit_imports((LABKIT / "stream" / "run.py").read_text(encoding="utf-8"))


def test_the_checker_sees_the_comparisons_it_forbids():
    assert protocol_name_uses('if protocol == "speed-sweep":\n    pass\n') == [1]
    assert protocol_name_uses('FIGURES.get(e.protocol)\n') == [1]
    assert protocol_name_uses('x = "spin-critical" in names\n') == [1]
    assert protocol_name_uses('TABLE[self.protocol]\n') == [1]
    assert protocol_name_uses('fit = LIVE_FITS.get(hints.fit)\nlabel = f"start {protocol}"\n') == []
