"""Names a package imports on first use (PEP 562), so ``import labkit.X`` and ``labkit --help``
do not load numpy, scipy, numba, OpenCV, matplotlib or rerun (tests/cli/test_startup.py)."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any


def lazy_attributes(package: str, homes: Mapping[str, str]) -> Callable[[str], Any]:
    """The module ``__getattr__`` of ``package``: ``name`` is imported from the module
    ``homes[name]`` on first access and kept in the package; any other name is an
    AttributeError, as for a plain module."""

    def __getattr__(name: str) -> Any:
        home = homes.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(home), name)
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__
