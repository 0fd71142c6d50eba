"""Reports: a self-contained folder (markdown + PNG figures) for a session or result file.

:func:`build_report` (``labkit report``) writes ``report.md`` with the run's metadata, events,
device flags (:func:`session_flags`), data, fits and figures. Imported on first use
(matplotlib is not loaded by ``import labkit.report``).
"""

from labkit.lazy import lazy_attributes

_PUBLIC = {"build_report": "labkit.report.build", "session_flags": "labkit.report.flags"}

__all__ = sorted(_PUBLIC)


__getattr__ = lazy_attributes(__name__, _PUBLIC)
