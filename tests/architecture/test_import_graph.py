"""The package import graph (read from the source with ``ast``, nothing imported):

* the transport (``labkit.io``) imports nothing from ``labkit.emulators`` (emulators own
  ``sim://``; docs/decisions/0005-emulators-own-sim-urls.md);
* no import cycle between labkit's top-level parts (``labkit.io``, ``labkit.devices``,
  ``labkit.rig``...), deferred imports inside functions included: a cycle means two parts that
  cannot be understood, tested or replaced one without the other.
"""

from __future__ import annotations

import ast
from pathlib import Path

from .import_rules import strongly_connected

LABKIT = Path(__file__).resolve().parents[2] / "labkit"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(LABKIT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported_modules(path: Path) -> set[str]:
    """Every ``labkit...`` module ``path`` imports, at module level or inside functions."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = module_name(path) if path.name == "__init__.py" else module_name(path).rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            out.add(target)
            out |= {f"{target}.{alias.name}" for alias in node.names}
    return {m for m in out if m == "labkit" or m.startswith("labkit.")}


def part(module: str) -> str:
    """``labkit.emulators.sim_port`` -> ``io``; ``labkit.errors`` -> ``errors``."""
    pieces = module.split(".")
    return pieces[1] if len(pieces) > 1 else ""


def part_graph() -> dict[str, set[str]]:
    """Top-level part -> the parts it imports (edges to itself and to ``labkit`` left out)."""
    known = {p.stem if p.is_file() else p.name for p in LABKIT.iterdir()  # namespace packages too
             if (p.suffix == ".py" and p.stem != "__init__") or (p.is_dir() and any(p.glob("*.py")))}
    graph: dict[str, set[str]] = {}
    for path in LABKIT.rglob("*.py"):
        src = part(module_name(path))
        if not src:
            continue
        for target in imported_modules(path):
            dst = part(target)
            if dst and dst != src and dst in known:
                graph.setdefault(src, set()).add(dst)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one part (Tarjan, :mod:`import_rules`)."""
    return strongly_connected(graph)


def edges_within(graph: dict[str, set[str]], comp: list[str]) -> list[str]:
    return [f"{a} -> {b}" for a in comp for b in sorted(graph.get(a, ())) if b in comp]


def test_the_transport_imports_no_emulator():
    offenders = {module_name(p): sorted(m for m in imported_modules(p) if part(m) == "emulators")
                 for p in (LABKIT / "io").rglob("*.py")}
    offenders = {k: v for k, v in offenders.items() if v}
    assert not offenders, f"labkit.io imports labkit.emulators: {offenders}"


def test_no_import_cycle_between_top_level_parts():
    graph = part_graph()
    found = cycles(graph)
    described = ["; ".join(edges_within(graph, comp)) for comp in found]
    assert not found, "import cycles between labkit's parts:\n  " + "\n  ".join(described)


def test_the_graph_reader_sees_relative_deferred_and_aliased_imports(tmp_path):
    """The checks above can fail: the reader finds the kinds of import they look for."""
    sample = LABKIT / "io" / "ports.py"
    assert "labkit.io.clock" in imported_modules(sample)
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []
