"""Typed run documents: every type round-trips through its JSON line (a reading with its stream's
descriptor, which declares its quantity and unit); a reading through ``Reading.values_json``
(flags and raw bytes included); the session's events.jsonl reads back as documents."""

from __future__ import annotations

import json
import math

from hypothesis import given
from hypothesis import strategies as st

from labkit import documents as doc
from labkit.protocols.launch import execute, prepare_run
from labkit.readings import Reading
from labkit.rig import bundled_rig_path
from labkit.session.writer import dumps

SAMPLES = [
    doc.RunStart(t=0.0, protocol="speed-sweep", params={"record_s": 1.0}, rig="r", n_steps=3,
                 session="/s", resumed_from=None),
    doc.StepStart(t=1.0, index=0, n_steps=3, label="up 6000 RPM", targets_rad_s={"rotor": 628.3}, eta_s=9.0),
    doc.Setpoint(t=1.0, loop="rotor", target_rad_s=628.3),
    doc.Settled(t=2.0, index=0, settle_time_s=1.5, speeds_rad_s={"rotor": 627.0}),
    doc.ControlSnapshot(t=2.1, loops={"rotor": {"target_rad_s": 628.3, "duty": 0.4}}),
    doc.StreamDescriptor(t=2.2, device="balance", kind="balance", driver="mtsics", quantity="mass",
                         unit="kg"),
    doc.ReadingEvent.of("balance", Reading(2.2, "mass", 0.0146, "kg", raw=b"S S 14.6 g\r\n",
                                           flags=frozenset({"device_reset", "tare_lost"}))),
    doc.Zeroed(t=0.5, device="balance", value=0.001, unit="kg"),
    doc.PointDone(t=3.0, index=0, point={"step": 0, "force_g": 4.0}),
    doc.FramesTaken(t=3.05, device="camera", index=0, take=1, seqs=[7, 8], times=[3.0, 3.033],
                    size=[320, 240], verdict="ok",
                    pattern={"type": "ellipse", "center_px": [160.0, 120.0], "semi_axes_px": [40, 30]},
                    pattern_at_y={"y": [1.0, 2.0], "semi_axes_px": [[20, 15], [40, 30]]}),
    doc.Drop(t=3.1, index=0, trial=1, rotor_rad_s=900.0, spin_rad_s=1200.0, cause="key", hold_s=2.0),
    doc.Checkpoint(t=3.2, index=0),
    doc.StopRequest(t=3.3, count=1, signal="SIGTERM"),
    doc.StopFailed(t=3.45, devices={"rotor_motor": "port gone (readiness to read but no data)"}),
    doc.Interlock(t=3.4, reason="tach silent", stop_failed=("rotor_motor: port gone",)),
    doc.Fault(t=3.5, reason="boom"),
    doc.Results(t=3.6, results={"points": [], "fit": {}}),
    doc.RunStop(t=3.7, status="completed", reason=None, steps_done=3),
]


def test_there_is_one_sample_per_document_type():
    assert {type(d) for d in SAMPLES} == set(doc.DOCUMENT_TYPES.values()) and len(doc.DOCUMENT_TYPES) == 18


def test_every_document_round_trips_through_its_json_line():
    stream = SAMPLES[5]
    for d in SAMPLES:
        line = dumps(d.to_json())
        assert doc.document_from_json(json.loads(line), stream) == d, line


def test_a_frames_document_keeps_the_frames_bytes_out_of_its_json_line():
    shot = doc.FramesTaken(t=1.0, device="camera", index=2, seqs=[1], times=[0.9], size=[8, 8],
                           payloads=(b"\xff\xd8 jpeg bytes",))
    line = shot.to_json()
    assert "payloads" not in line and line["seqs"] == [1] and line["device"] == "camera"
    back = doc.document_from_json(json.loads(dumps(line)))
    assert back.payloads == () and back.seqs == [1] and back.index == 2


def test_a_reading_document_is_the_readings_own_values_without_units():
    d = SAMPLES[6]
    assert d.to_json() == {"type": "reading", "run_id": "", "device": "balance", **d.reading.values_json()}
    assert d.to_json()["flags"] == ["device_reset", "tare_lost"] and d.to_json()["raw"] == "S S 14.6 g\r\n"
    assert "unit" not in d.to_json() and "quantity" not in d.to_json()


def test_an_unknown_type_or_missing_field_is_named():
    for bad, words in (({"type": "nonsense", "t": 0}, "nonsense"), ({"type": "fault", "t": 0}, "reason")):
        try:
            doc.document_from_json(bad)
        except doc.UnknownDocument as exc:
            assert words in str(exc)
        else:
            raise AssertionError(f"{bad} was accepted")


@given(t=st.floats(allow_nan=False, allow_infinity=False), value=st.floats(), raw=st.binary(max_size=40),
       flags=st.frozensets(st.sampled_from(["device_reset", "tare_lost", "overload", "resync"])),
       stable=st.booleans())
def test_fuzz_reading_json_round_trip(t, value, raw, flags, stable):
    r = Reading(t, "force", value, "N", stable=stable, overload=not math.isfinite(value), raw=raw,
                flags=flags)
    back = Reading.from_json(json.loads(json.dumps(r.as_json(), allow_nan=False)))
    assert back.raw == raw and back.flags == flags and back.stable == stable and back.t == t
    assert back.value == value if math.isfinite(value) else math.isnan(back.value)


def test_a_sessions_events_read_back_as_documents(tmp_path):
    prep = prepare_run(str(bundled_rig_path("emulated-fig525")), "speed-sweep",
                       ["speeds_rpm=6000:9000:3000", "record_s=0.5"], clock="virtual", session_root=tmp_path)
    outcome = execute(prep, tmp_path)
    lines = (outcome.session / "events.jsonl").read_text().splitlines()
    docs = [doc.document_from_json(json.loads(line)) for line in lines]
    kinds = [d.type for d in docs]
    assert kinds[0] == "start" and kinds[-1] == "stop" and kinds.count("point") == 2
    assert "reading" not in kinds                         # readings go to readings/ROLE.jsonl
    assert isinstance(docs[-1], doc.RunStop) and docs[-1].status == "completed"
