"""The import rules can fail: each finds what it looks for in a package planted in a temporary
directory, and lets pass what it must (TYPE_CHECKING imports, dunders, a parent's own names)."""

from __future__ import annotations

from pathlib import Path

from .import_rules import import_cycles, layer_violations, private_imports


def plant(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return root / "pkg"


def test_a_cycle_through_an_import_inside_a_function_is_found(tmp_path):
    package = plant(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/a.py": "from pkg.b import f\n",
        "pkg/b.py": "def f():\n    from . import c\n    return c\n",
        "pkg/c.py": "import pkg.a\n",
        "pkg/d.py": "from pkg import a\n",
    })
    (cycle,) = import_cycles(package)
    assert cycle.startswith("3 modules: ")
    assert "pkg.b -> pkg.c" in cycle and "pkg.c -> pkg.a" in cycle and "pkg.d" not in cycle


def test_a_package_that_imports_its_own_subpackage_back_is_a_cycle(tmp_path):
    package = plant(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/base.py": "def register():\n    from pkg.drivers import one\n",
        "pkg/drivers/__init__.py": "",
        "pkg/drivers/one.py": "from ..base import register\n",
    })
    assert import_cycles(package) == ["2 modules: pkg.base -> pkg.drivers.one; pkg.drivers.one -> pkg.base"]


def test_imports_under_type_checking_are_not_counted(tmp_path):
    package = plant(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/a.py": "import typing\nif typing.TYPE_CHECKING:\n    from pkg.b import _B\nimport pkg.b\n",
        "pkg/b.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.a import x\n"
                    "else:\n    x = None\n",
    })
    assert import_cycles(package) == []
    assert private_imports(package) == []


def test_a_private_name_from_another_module_is_found(tmp_path):
    package = plant(tmp_path, {
        "pkg/__init__.py": "from pkg._version import __version__\n",
        "pkg/_version.py": "__version__ = '1'\n",
        "pkg/a.py": "_x = 1\n__all__ = ['_x']\n",
        "pkg/b.py": "def f():\n    from .a import _x, __all__\n    return _x\n",
    })
    assert private_imports(package) == ["pkg/b.py:2 imports _x from pkg.a"]


def test_an_import_against_the_layer_order_is_found(tmp_path):
    package = plant(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/low.py": "def f():\n    from pkg.high import g\n",
        "pkg/high/__init__.py": "from pkg import low\n",
        "pkg/stray.py": "",
    })
    found = layer_violations(package, [{"low"}, {"high"}])
    assert found == ["stray is in no layer", "pkg.low:2 (low, layer 0) imports pkg.high (high, layer 1)"]
    assert layer_violations(package, [{"low", "high", "stray"}]) == []
