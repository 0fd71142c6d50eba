"""labkit's import rules read from the source with ``ast`` (nothing is imported): pure functions
over a package directory, used by the architecture tests on ``labkit/`` and, in their own unit
tests, on small packages planted in a temporary directory (so each rule is seen to fail).

* An *import* is every ``import``/``from ... import`` statement in a module, at module level or
  inside a function, except those under ``if TYPE_CHECKING:`` (they never run).
* ``from package import name`` depends on ``package.name`` when that is a module, else on
  ``package`` (whose ``__init__`` defines the name).
* A *cycle inside a package* is a set of two or more modules that import each other, directly or
  through others (a strongly connected component of the module graph).
* A *private import* is ``from module import _name`` naming another module's private name
  (one leading underscore; dunders such as ``__version__`` are public; a private module is not
  a name and not counted).
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Import:
    """One imported name: ``module`` depends on ``target`` (a module); ``name`` is the name taken
    from it (``None`` for ``import target``)."""

    module: str
    target: str
    name: str | None
    line: int


def module_name(path: Path, root: Path) -> str:
    """``root/labkit/io/ports.py`` -> ``labkit.io.ports``; a package's ``__init__`` is the package."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules_of(package: Path) -> dict[str, Path]:
    """Every module of the package directory ``package`` by dotted name."""
    return {module_name(p, package.parent): p for p in sorted(package.rglob("*.py"))}


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _import_nodes(tree: ast.AST) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement that can run: the body of ``if TYPE_CHECKING:`` is skipped (its
    ``else:`` is not)."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        elif isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                yield from _import_nodes(ast.Module(body=[child], type_ignores=[]))
        else:
            yield from _import_nodes(node)


def _absolute(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(path: Path, module: str, known: set[str]) -> list[Import]:
    """The imports of one module (``known``: the modules of the package tree, to tell a submodule
    from a name)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    out: list[Import] = []
    for node in _import_nodes(tree):
        if isinstance(node, ast.Import):
            out += [Import(module, alias.name, None, node.lineno) for alias in node.names]
            continue
        source = _absolute(node, module, path.name == "__init__.py")
        for alias in node.names:
            sub = f"{source}.{alias.name}"
            if sub in known:
                out.append(Import(module, sub, None, node.lineno))
            else:
                out.append(Import(module, source, alias.name, node.lineno))
    return out


def all_imports(package: Path) -> list[Import]:
    """Every import inside the package tree that names one of its own modules."""
    modules = modules_of(package)
    known = set(modules)
    return [imp for name, path in modules.items() for imp in imports_of(path, name, known)
            if imp.target in known]


def module_graph(imports: list[Import]) -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for imp in imports:
        if imp.target != imp.module:
            graph.setdefault(imp.module, set()).add(imp.target)
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one node, each sorted (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, successors = work[-1]
            for w in successors:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        out.append(sorted(component))
    return sorted(out)


def describe_cycle(graph: dict[str, set[str]], component: list[str]) -> str:
    inside = set(component)
    edges = [f"{a} -> {b}" for a in component for b in sorted(graph.get(a, ())) if b in inside]
    return f"{len(component)} modules: " + "; ".join(edges)


def import_cycles(package: Path) -> list[str]:
    """One line per cycle among the package tree's modules."""
    graph = module_graph(all_imports(package))
    return [describe_cycle(graph, c) for c in strongly_connected(graph)]


def is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports(package: Path) -> list[str]:
    """One line per private name imported from another module of the package tree (a module
    whose own name starts with ``_`` is its package's business and not counted)."""
    modules = modules_of(package)
    found = []
    for imp in all_imports(package):
        if imp.name is not None and imp.target != imp.module and is_private(imp.name):
            where = modules[imp.module].relative_to(package.parent)
            found.append(f"{where}:{imp.line} imports {imp.name} from {imp.target}")
    return found


def top_level(module: str) -> str:
    """``labkit.io.ports`` -> ``io``; ``labkit.errors`` -> ``errors``; ``labkit`` -> ``""``."""
    pieces = module.split(".")
    return pieces[1] if len(pieces) > 1 else ""


def layer_violations(package: Path, layers: list[set[str]]) -> list[str]:
    """Imports of a top-level part from a part in a higher layer (``layers`` from the bottom up;
    a part may import its own layer's parts and those below). A part in no layer is reported."""
    level = {name: i for i, layer in enumerate(layers) for name in layer}
    parts = {top_level(m) for m in modules_of(package)} - {""}
    found = [f"{p} is in no layer" for p in sorted(parts - set(level))]
    for imp in all_imports(package):
        src, dst = top_level(imp.module), top_level(imp.target)
        if src and dst and src != dst and src in level and dst in level and level[dst] > level[src]:
            found.append(f"{imp.module}:{imp.line} ({src}, layer {level[src]}) imports {imp.target} "
                         f"({dst}, layer {level[dst]})")
    return found
