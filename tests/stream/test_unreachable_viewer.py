"""`--rerun connect:ADDR` with no viewer there: closing the run's rerun sink gives up after
FLUSH_TIMEOUT_S and says why, instead of hanging in rerun's flush after the session is saved
(`labkit run` then prints one line: "rerun viewer not reached, live view incomplete")."""

import pytest
import rerun as rr

import labkit.stream.run as stream_run
from labkit import documents as doc


@pytest.mark.timeout(60)   # before the fix this never returned
def test_closing_a_sink_whose_viewer_never_answered_returns_with_the_reason(monkeypatch):
    monkeypatch.setattr(stream_run, "FLUSH_TIMEOUT_S", 0.5)
    rec = rr.RecordingStream("labkit-test-unreachable")
    rec.connect_grpc("rerun+http://127.0.0.1:1/proxy")       # nothing listens on port 1
    sink = stream_run.RerunRunSink(rec)
    sink.on_event(doc.RunStart(t=0.0, protocol="speed-sweep", params={}, rig="r", n_steps=1))
    sink.on_event(doc.Setpoint(t=0.1, loop="rotor", target_rad_s=628.3))
    sink.close()
    assert sink.flush_error
