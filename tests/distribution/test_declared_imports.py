"""Every third-party package that labkit/ imports is declared in pyproject.toml (issue 18, item 6).

Walks every module of labkit/ with ``ast``, maps each top-level import that is neither the
standard library nor labkit to its distribution (``importlib.metadata.packages_distributions``,
i.e. what is installed here), and checks that distribution is a dependency or an extra.
"""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from importlib.metadata import packages_distributions
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def declared() -> dict[str, str]:
    """canonical distribution name -> where it is declared (``dependencies`` or ``extra NAME``)."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    out = {}
    groups = [("dependencies", project["dependencies"])]
    groups += [(f"extra {k}", v) for k, v in project.get("optional-dependencies", {}).items()]
    for where, requirements in groups:
        for requirement in requirements:
            out[canonical(re.split(r"[\s\[<>=!~;]", requirement, maxsplit=1)[0])] = where
    return out


def imported_top_levels(root: Path) -> dict[str, list[str]]:
    """top-level module -> files of labkit/ importing it (absolute imports only)."""
    found: dict[str, list[str]] = {}
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            for name in names:
                found.setdefault(name.split(".")[0], []).append(str(path.relative_to(root)))
    return found


def third_party(found: dict[str, list[str]]) -> dict[str, list[str]]:
    return {m: files for m, files in found.items()
            if m not in sys.stdlib_module_names and m not in ("labkit", "__future__")}


def test_every_imported_package_is_declared() -> None:
    modules = third_party(imported_top_levels(REPO / "labkit"))
    assert {"numpy", "serial", "pandas", "pyarrow"} <= set(modules)  # the walk sees real imports
    dists = packages_distributions()
    wanted = declared()
    missing = []
    for module, files in sorted(modules.items()):
        candidates = [canonical(d) for d in dists.get(module, [])]
        if not candidates:
            missing.append(f"{module} (imported by {files[0]}) is not installed, so not declared")
        elif not any(c in wanted for c in candidates):
            missing.append(f"{module} -> {candidates} (imported by {files[0]}) is not in pyproject.toml")
    assert not missing, "\n".join(missing)


def test_the_check_catches_an_undeclared_import(tmp_path: Path) -> None:
    (tmp_path / "m.py").write_text("import yaml_that_is_not_declared.sub\nimport json\n"
                                   "from numpy import array\nfrom . import sibling\n")
    assert set(third_party(imported_top_levels(tmp_path))) == {"yaml_that_is_not_declared", "numpy"}
    assert "yaml-that-is-not-declared" not in declared()
    assert declared()["numpy"] == "dependencies"


def test_test_tools_have_compatible_ranges() -> None:
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    test_extra = project["optional-dependencies"]["test"]
    for tool in ("pytest", "hypothesis", "pytest-timeout", "ruff"):
        (spec,) = [r for r in test_extra if canonical(re.split(r"[<>=]", r, maxsplit=1)[0]) == tool]
        assert ">=" in spec and "<" in spec.replace("<=", ""), f"{spec}: needs a lower and an upper bound"
