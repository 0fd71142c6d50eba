"""Reading streams (docs/decisions/0033-one-reading-shape.md): a device's stream declares its
quantity and unit once, in a descriptor before its first reading; readings carry values only;
every document carries the run's id, and a resumed run's documents carry the id of the run it
resumes. Sessions written before descriptors (every reading with its own unit) still read."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from labkit import documents as doc
from labkit.protocols.events import ListSink
from labkit.protocols.launch import execute, prepare_run
from labkit.readings import Reading, declared
from labkit.rig import bundled_rig_path
from labkit.session import export_csv, load_session_record

REPO = Path(__file__).resolve().parents[2]
SWEEP = ["speeds_rpm=6000:9000:3000", "record_s=0.5"]


def _lines(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    root = tmp_path_factory.mktemp("sessions")
    seen = ListSink()
    prep = prepare_run(str(bundled_rig_path("emulated-fig525")), "speed-sweep", SWEEP, clock="virtual",
                       session_root=root, sinks=[seen])
    outcome = execute(prep, root)
    assert outcome.status == "completed", outcome.reason
    return outcome.session, seen.events


def test_each_stream_is_described_once_before_its_first_reading(sweep):
    _, events = sweep
    streams = {e.device for e in events if isinstance(e, doc.ReadingEvent)}
    assert {"balance", "rotor_tach"} <= streams
    for device in streams:
        mine = [e for e in events
                if isinstance(e, doc.ReadingEvent | doc.StreamDescriptor) and e.device == device]
        assert isinstance(mine[0], doc.StreamDescriptor), device
        assert sum(isinstance(e, doc.StreamDescriptor) for e in mine) == 1, device
        described = mine[0]
        assert all(described.declares(e.reading) for e in mine[1:])
    balance = next(e for e in events if isinstance(e, doc.StreamDescriptor) and e.device == "balance")
    assert (balance.kind, balance.driver, balance.unit) == ("balance", "mtsics", "kg")


def test_the_readings_file_holds_the_descriptor_then_values_without_units(sweep):
    session, _ = sweep
    for path in sorted((session / "readings").glob("*.jsonl")):
        first, *rows = _lines(path)
        assert first["type"] == "descriptor" and first["device"] == path.stem and first["unit"]
        assert rows and all("unit" not in r and "quantity" not in r and "type" not in r for r in rows), path
    # read back with the stream's units, as every line carried them before descriptors
    readings = load_session_record(session).readings("balance")
    assert readings and {(r["quantity"], r["unit"]) for r in readings} == {("mass", "kg")}
    # and so does the CSV export, one row per reading
    [csv_path] = [p for p in export_csv(session) if p.stem == "balance"]
    rows = list(csv.DictReader(csv_path.open()))
    assert len(rows) == len(readings) and {(r["quantity"], r["unit"]) for r in rows} == {("mass", "kg")}


def test_every_document_carries_the_runs_id(sweep):
    session, events = sweep
    run_id = json.loads((session / "run.json").read_text())["run_id"]
    assert len(run_id) == 36                                          # a uuid
    assert {e.run_id for e in events} == {run_id}
    assert {e["run_id"] for e in _lines(session / "events.jsonl")} == {run_id}
    assert all(_lines(p)[0]["run_id"] == run_id for p in (session / "readings").glob("*.jsonl"))
    assert load_session_record(session).run_id == run_id


class _StopAfterFirstPoint:
    """Asks the run to stop (as one Ctrl-C does) once its first point is done."""

    def __init__(self) -> None:
        self.runner = None

    def on_event(self, event) -> None:
        if event.type == "point" and self.runner is not None and self.runner.stop_count == 0:
            self.runner.request_stop()


def test_a_resumed_run_carries_the_run_id_of_the_run_it_resumes(tmp_path):
    stopper = _StopAfterFirstPoint()
    prep = prepare_run(str(bundled_rig_path("emulated-fig525")), "speed-sweep", SWEEP, clock="virtual",
                       session_root=tmp_path, sinks=[stopper])
    stopper.runner = prep.runner
    first = execute(prep, tmp_path)
    assert first.status == "interrupted", first.reason
    seen = ListSink()
    again = prepare_run(None, None, None, clock="virtual", session_root=tmp_path, resume=first.session,
                        sinks=[seen])
    second = execute(again, tmp_path)
    assert second.status == "completed" and second.session != first.session
    first_id = load_session_record(first.session).run_id
    assert first_id and load_session_record(second.session).run_id == first_id
    assert {e["run_id"] for e in _lines(second.session / "events.jsonl")} == {first_id}
    assert {e.run_id for e in seen.events} == {first_id}
    described = [_lines(p)[0] for p in (second.session / "readings").glob("*.jsonl")]
    assert described and {d["run_id"] for d in described} == {first_id}


def test_a_stream_whose_unit_changes_is_described_again(tmp_path):
    rows = [{"type": "descriptor", "t": 0.0, "device": "balance", "quantity": "mass", "unit": "kg"},
            Reading(0.1, "mass", 0.01, "kg").values_json(),
            {"type": "descriptor", "t": 0.2, "device": "balance", "quantity": "force", "unit": "N"},
            Reading(0.2, "force", 0.1, "N").values_json()]
    back = [Reading.from_json(r) for _, r in declared(enumerate(rows, 1))]
    assert [(r.quantity, r.unit, r.value) for r in back] == [("mass", "kg", 0.01), ("force", "N", 0.1)]


def test_a_readings_file_from_before_descriptors_reads_as_it_did():
    old = [Reading(0.1, "mass", 0.01, "kg", raw=b"S S 10.0 g").as_json(),
           Reading(0.2, "mass", 0.02, "kg", raw=b"S S 20.0 g").as_json()]
    assert [r for _, r in declared(enumerate(old, 1))] == old
    shipped = REPO / "recordings" / "sessions" / "speed-sweep-clean"
    readings = load_session_record(shipped).readings("balance")
    assert readings and all(r["unit"] == "kg" and r["quantity"] == "mass" for r in readings)
    assert load_session_record(shipped).run_id is None          # recorded before run ids


UNITS = st.sampled_from([("mass", "kg"), ("force", "N"), ("angular_speed", "rad/s")])


@given(st.lists(st.tuples(UNITS, st.floats(allow_nan=False, allow_infinity=False), st.binary(max_size=12)),
                max_size=20))
def test_fuzz_a_described_stream_reads_back_as_whole_readings(items):
    """However often a stream's unit changes, writing it as descriptors plus values and reading
    it back with :func:`declared` gives every reading whole, as :meth:`Reading.as_json` has it."""
    written, current = [], None
    readings = [Reading(float(i), q, v, u, raw=raw) for i, ((q, u), v, raw) in enumerate(items)]
    for r in readings:
        if current != (r.quantity, r.unit):
            current = (r.quantity, r.unit)
            written.append(doc.StreamDescriptor.of("balance", r).to_json())
        written.append(r.values_json())
    lines = [json.loads(json.dumps(x)) for x in written]
    assert [row for _, row in declared(enumerate(lines, 1))] == [json.loads(json.dumps(r.as_json()))
                                                                 for r in readings]
