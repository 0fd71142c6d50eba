"""Small modules with one job: no module in labkit/ over 500 lines, no function over 100 lines
(issue 12's acceptance; docs/explanation/developing.md, Rules)."""

from __future__ import annotations

import ast
from pathlib import Path

LABKIT = Path(__file__).resolve().parents[2] / "labkit"
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 100


def test_no_module_is_over_500_lines():
    long = {str(p.relative_to(LABKIT.parent)): n for p in LABKIT.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES}
    assert not long, long


def test_no_function_is_over_100_lines():
    long = []
    for path in LABKIT.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    where = f"{path.relative_to(LABKIT.parent)}:{node.lineno}"
                    long.append(f"{where} {node.name} ({lines} lines)")
    assert not long, long


def test_the_limits_can_fail(tmp_path):
    source = "def f():\n" + "    x = 1\n" * 120
    (node,) = ast.parse(source).body
    assert node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES
