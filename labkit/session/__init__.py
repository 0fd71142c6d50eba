"""Run directories: append-only, crash-safe, resumable (see writer.py for the layout).

:func:`load_session_record` reads one back as a :class:`SessionRecord` (dicts, as written);
``labkit.load_session`` gives the same session as pandas DataFrames. ``labkit.session.load_session``
is the old name of :func:`load_session_record`, kept as a deprecated alias
(docs/decisions/0035-one-name-per-thing.md).
"""

from typing import Any

from labkit.errors import SessionError
from labkit.session.export import export_csv, read_jsonl
from labkit.session.reader import SessionRecord, load_session_record
from labkit.session.writer import Session, check_writable, new_session_dir


def __getattr__(name: str) -> Any:
    if name == "load_session":
        import warnings

        warnings.warn("labkit.session.load_session is labkit.session.load_session_record now (a "
                      "SessionRecord); labkit.load_session gives DataFrames", DeprecationWarning,
                      stacklevel=2)
        return load_session_record
    raise AttributeError(f"module 'labkit.session' has no attribute {name!r}")


__all__ = [
    "Session", "SessionError", "SessionRecord", "check_writable", "export_csv", "load_session_record",
    "new_session_dir", "read_jsonl",
]
