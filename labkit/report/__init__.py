"""Reports: a self-contained folder (markdown + PNG figures) for a session or result file.

:func:`build_report` (``labkit report``) writes ``report.md`` with the run's metadata, events,
device flags (:func:`session_flags`), data, fits and figures. Imported on first use
(matplotlib is not loaded by ``import labkit.report``).
"""

from importlib import import_module
from typing import Any

_PUBLIC = {"build_report": "labkit.report.build", "session_flags": "labkit.report.flags"}

__all__ = sorted(_PUBLIC)


def __getattr__(name: str) -> Any:
    if name in _PUBLIC:
        return getattr(import_module(_PUBLIC[name]), name)
    raise AttributeError(f"module 'labkit.report' has no attribute {name!r}")
