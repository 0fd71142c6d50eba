"""The path of one balance reading, from the serial bytes to the session file and the rerun
stream, counted (issue 24 asks for at most 8 files and 4 data shapes; here 8 and 4:
docs/decisions/0033-one-reading-shape.md).

:data:`PATH` is the path as it is: each hop a file, the function in it the reading passes
through, and the shape it hands on. Each hop is checked against the code (the function exists
and names the shape it builds or the call that carries it on), so the table cannot drift from
the code unnoticed; the counts cannot grow without this file being edited, in review.

Files are counted where the reading's data is built, converted or written; the event bus
(:mod:`labkit.protocols.events`: stamps the run id on the document) and the session guard
(:mod:`labkit.protocols.exit_paths`: the session sink's failure policy) hand the document on
unread and are listed in :data:`PASSED_THROUGH`. rerun-sdk's own code and the port under the
link (``record://`` taps the same bytes into the cassette) are not counted.
"""

from __future__ import annotations

import ast
import inspect
import textwrap
from collections.abc import Callable
from pathlib import Path
from typing import Any

from labkit import units
from labkit.devices import link
from labkit.devices.registry import driver_class
from labkit.documents import ReadingEvent
from labkit.protocols.context import RunContext
from labkit.protocols.events import EventBus
from labkit.protocols.exit_paths import SessionGuard
from labkit.readings import Reading
from labkit.session.writer import Session
from labkit.stream.run import RerunRunSink

LABKIT = Path(__file__).resolve().parents[2] / "labkit"
MTSICS = driver_class("balance", "mtsics")

#: (the function a reading passes through, a name it must use, the shape it hands on); files
#: are found from the functions, so a module moved or renamed keeps its hop
PATH: list[tuple[Callable[..., Any], str, str]] = [
    (link.LineLink.pull, "_frame", "bytes"),                    # the port's bytes, into lines
    (link.LineFramer.feed, "terminator", "bytes"),              # a frame's bytes (the link's framer)
    (MTSICS._reading, "parse_weight", "MtWeight"),              # the driver's parsed frame
    # display unit -> SI: (quantity, value, unit) returned straight into the Reading's fields
    (units.to_si, "KG_PER_UNIT", "Reading"),
    (Reading.values_json, "as_json", "Reading"),
    (RunContext.emit_reading, "StreamDescriptor", "ReadingEvent"),   # a descriptor before a stream
    (ReadingEvent.of, "reading", "ReadingEvent"),
    (Session.on_event, "values_json", "ReadingEvent"),          # its line in readings/ROLE.jsonl
    (RerunRunSink._on_reading, "series", "ReadingEvent"),       # its rerun scalar
]
#: hand the document on unread: the run id stamped, the session sink's failure policy
PASSED_THROUGH: list[tuple[Callable[..., Any], str]] = [(EventBus.emit, "sinks"),
                                                        (SessionGuard.on_event, "on_event")]
#: issue 24's caps
MAX_FILES = 8
MAX_SHAPES = 4


def _function(fn: Callable[..., Any]) -> ast.AST:
    return ast.parse(textwrap.dedent(inspect.getsource(fn)))


def _file(fn: Callable[..., Any]) -> str:
    return str(Path(inspect.getsourcefile(fn) or "?").resolve().relative_to(LABKIT))


def _names(node: ast.AST) -> set[str]:
    out: set[str] = set()
    for n in ast.walk(node):
        if isinstance(n, ast.Name):
            out.add(n.id)
        elif isinstance(n, ast.Attribute):
            out.add(n.attr)
    return out


def test_every_hop_of_the_path_is_in_the_code():
    for fn, named in [(fn, named) for fn, named, _ in PATH] + PASSED_THROUGH:
        assert named in _names(_function(fn)), (
            f"labkit/{_file(fn)} {fn.__qualname__} no longer uses {named}: the reading's path changed "
            "(update PATH and ADR 0033)")


def test_a_balance_reading_crosses_at_most_8_files_and_4_shapes():
    files = {_file(fn) for fn, *_ in PATH}
    shapes = {shape for *_, shape in PATH}
    assert len(files) <= MAX_FILES, sorted(files)
    assert len(shapes) <= MAX_SHAPES, sorted(shapes)
    assert len(files | {_file(fn) for fn, _ in PASSED_THROUGH}) <= MAX_FILES + 2


def test_the_session_writer_and_the_rerun_sink_take_units_from_the_descriptor_only():
    """Neither sink reads a reading's unit or quantity: the writer writes values only, the rerun
    sink draws a stream as its descriptor says (a reading without one: its own, the fallback)."""
    writer = _names(_function(Session.on_event))
    assert "unit" not in writer and "quantity" not in writer and "as_json" not in writer
    drawn = _function(RerunRunSink._on_descriptor)
    assert {"quantity", "unit"} <= _names(drawn)


def test_one_module_converts_a_balance_reading_to_grams_force():
    """``G0`` and the grams-force factor appear in labkit/units.py only among the modules a
    reading's value passes through or is averaged in (sinks, documents, protocols)."""
    for part in ("stream", "session", "protocols", "documents.py", "readings.py", "report"):
        root = LABKIT / part
        for path in ([root] if root.is_file() else sorted(root.rglob("*.py"))):
            text = path.read_text()
            assert "9.80665" not in text and "/ G0" not in text and "* G0" not in text, path
