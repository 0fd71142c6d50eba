"""The public faces: each package a script uses has a curated ``__all__`` whose names resolve,
and docs/how-to/script-labkit.md imports nothing but those names."""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

import pytest

FACES = ("labkit.devices", "labkit.io", "labkit.emulators", "labkit.model", "labkit.vision",
         "labkit.vision.laser", "labkit.vision.strobe", "labkit.report", "labkit.protocols", "labkit.fit",
         "labkit.rig")
PAGE = Path(__file__).resolve().parents[2] / "docs" / "how-to" / "script-labkit.md"


@pytest.mark.parametrize("name", FACES)
def test_every_name_of_all_resolves(name):
    module = importlib.import_module(name)
    assert module.__all__ and len(set(module.__all__)) == len(module.__all__)
    assert [n for n in module.__all__ if not hasattr(module, n)] == []


def test_the_scripting_page_imports_only_public_names():
    code = "\n".join(re.findall(r"```python\n(.*?)```", PAGE.read_text(), re.S))
    private = []
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("labkit"):
            module = importlib.import_module(node.module)
            public = getattr(module, "__all__", None)
            private += [f"{node.module}.{a.name}" for a in node.names
                        if public is None or a.name not in public]
    assert private == []
