"""The live view draws whatever figure the start document's hints declare, and says so when it
has no live fit for the hinted model instead of silently drawing points alone (ADR 0021)."""

from __future__ import annotations

import rerun as rr

import labkit.stream.run as stream_run
from labkit import documents as doc
from labkit.hints import Hints
from labkit.stream.livefit import LIVE_FITS
from labkit.stream.readback import column, entity_paths


def event_texts(path) -> list[str]:
    """Every text logged to ``/events`` (chunks differ in their timelines, so read each)."""
    from rerun.chunk import RrdReader

    out = []
    for chunk in RrdReader(str(path)).stream().filter(content="/events", is_static=False):
        batch = chunk.to_record_batch()
        if "TextLog:text" in batch.schema.names:
            out += [t[0] for t in batch.column("TextLog:text").to_pylist()]
    return out


def stream_points(path, hints: Hints, points: list[dict]) -> None:
    rec = rr.RecordingStream("labkit-test-hints")
    rec.save(str(path))
    sink = stream_run.RerunRunSink(rec)
    sink.on_event(doc.RunStart(t=0.0, protocol="my-protocol", params={}, rig="r", n_steps=len(points),
                               hints=hints.to_json()))
    for i, point in enumerate(points):
        sink.on_event(doc.StepStart(t=i + 0.5, index=i, n_steps=len(points), label=f"{i}",
                                    targets_rad_s={"rotor": 100.0 * (i + 1)}))
        sink.on_event(doc.PointDone(t=i + 1.0, index=i, point=point))
    sink.close()


def test_a_hinted_model_without_a_live_fit_is_named_in_the_events(tmp_path):
    hints = Hints("w_rad_s", "gap_um", "rotor speed", "rad/s", "gap", "um", figure="Gap", fit="powerlaw")
    points = [{"w_rad_s": 100.0 * k, "gap_um": 50.0 / k} for k in range(1, 5)]
    stream_points(tmp_path / "r.rrd", hints, points)
    entities = entity_paths(tmp_path / "r.rrd")
    assert "/gap/plot/data" in entities and not any(e.startswith("/gap/plot/fit") for e in entities)
    warned = [t for t in event_texts(tmp_path / "r.rrd") if "no live fit" in t]
    known = ", ".join(sorted(LIVE_FITS))   # the registry is open: other protocols add theirs
    assert "power-law, spin-critical" in known
    assert warned == [f"my-protocol: no live fit for model 'powerlaw' (known: {known}); "
                      "points are drawn without a fit"]


def test_the_same_points_with_a_known_model_get_their_fit(tmp_path):
    hints = Hints("w_rad_s", "gap_um", "rotor speed", "rad/s", "gap", "um", figure="Gap", fit="power-law")
    points = [{"w_rad_s": 100.0 * k, "gap_um": 50.0 / k} for k in range(1, 5)]
    stream_points(tmp_path / "r.rrd", hints, points)
    entities = entity_paths(tmp_path / "r.rrd")
    assert {"/gap/plot/fit/after_03", "/gap/plot/fit/after_04", "/gap/residual/after_04"} <= entities
    x, y = column(tmp_path / "r.rrd", "/gap/plot/data", "Scalars:scalars", "rotor speed [rad/s]")
    assert x == [100, 200, 300, 400] and [v[0] for v in y] == [50.0, 25.0, 50.0 / 3, 12.5]


def test_a_point_marked_inconsistent_is_drawn_but_left_out_of_the_live_fit(tmp_path):
    hints = Hints("w_rad_s", "gap_um", "rotor speed", "rad/s", "gap", "um", figure="Gap", fit="power-law")
    points = [{"w_rad_s": 100.0 * k, "gap_um": 50.0 / k, "consistent": k != 3} for k in range(1, 6)]
    stream_points(tmp_path / "r.rrd", hints, points)
    entities = entity_paths(tmp_path / "r.rrd")
    # five points drawn, the fit made of the four consistent ones (after_04 is the last)
    x, _ = column(tmp_path / "r.rrd", "/gap/plot/data", "Scalars:scalars", "rotor speed [rad/s]")
    assert x == [100, 200, 300, 400, 500]
    assert "/gap/plot/fit/after_04" in entities and "/gap/plot/fit/after_05" not in entities
    assert any("left out of the live fit" in t for t in event_texts(tmp_path / "r.rrd"))


def test_a_point_whose_analysis_is_not_ok_is_drawn_but_left_out_of_the_live_fit(tmp_path):
    """A row's ``verdict`` (cone-sweep: the burst analysis's) other than ok keeps the point out of
    the live fit, as the protocol's own fit leaves it out, and the events say why."""
    hints = Hints("w_rad_s", "gap_um", "rotor speed", "rad/s", "gap", "um", figure="Gap", fit="power-law")
    points = [{"w_rad_s": 100.0 * k, "gap_um": 50.0 / k, "verdict": "doubtful" if k == 2 else "ok",
               "reasons": ["trace touches the frame's edge"] if k == 2 else []} for k in range(1, 6)]
    stream_points(tmp_path / "r.rrd", hints, points)
    x, _ = column(tmp_path / "r.rrd", "/gap/plot/data", "Scalars:scalars", "rotor speed [rad/s]")
    assert x == [100, 200, 300, 400, 500]
    entities = entity_paths(tmp_path / "r.rrd")
    assert "/gap/plot/fit/after_04" in entities and "/gap/plot/fit/after_05" not in entities
    assert any("verdict is doubtful (trace touches the frame's edge)" in t
               for t in event_texts(tmp_path / "r.rrd"))


def test_also_columns_are_drawn_against_the_same_x_and_a_missing_value_is_skipped(tmp_path):
    from labkit.hints import Series

    hints = Hints("speed_rpm", "phi_deg", "rotor speed", "RPM", "phi", "deg", figure="Eq. 5.97",
                  also=(Series("beta_mm", "beta", "mm"), Series("delta_mm", "delta", "mm")))
    points = [{"speed_rpm": 4000.0 + 1000 * k, "phi_deg": 12.0 / (k + 1), "beta_mm": 0.6 / (k + 1),
               "delta_mm": 2.6 if k != 2 else None} for k in range(4)]
    stream_points(tmp_path / "r.rrd", hints, points)
    x, y = column(tmp_path / "r.rrd", "/eq_5_97/also/beta_mm", "Scalars:scalars", "rotor speed [RPM]")
    assert x == [4000, 5000, 6000, 7000] and [v[0] for v in y] == [0.6 / (k + 1) for k in range(4)]
    x, y = column(tmp_path / "r.rrd", "/eq_5_97/also/delta_mm", "Scalars:scalars", "rotor speed [RPM]")
    assert x == [4000, 5000, 7000] and [v[0] for v in y] == [2.6, 2.6, 2.6]
