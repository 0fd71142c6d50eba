"""``labkit.load_session(PATH)``: a session as DataFrames (issue 18 acceptance)."""

from __future__ import annotations

from pathlib import Path

import pytest

import labkit

RIGS = Path(__file__).resolve().parents[2] / "rigs"


@pytest.fixture(scope="module")
def sweep(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("sessions")
    prep = labkit.prepare_run(str(RIGS / "emulated-fig525.toml"), "speed-sweep",
                              ["speeds_rpm=6000:10000:1000", "record_s=1"], clock="virtual",
                              session_root=str(root))
    outcome = labkit.execute(prep, str(root))
    assert outcome.status == "completed"
    return Path(outcome.session)


def test_a_five_step_sweep_is_five_points_and_balance_readings(sweep: Path) -> None:
    session = labkit.load_session(sweep)
    points = session.points
    assert len(points) == 5
    assert {"speed_rpm", "force_g", "force_stderr_g", "speed_std_rpm"} <= set(points.columns)
    assert points["speed_rpm"].is_monotonic_increasing
    balance = session.readings["balance"]
    assert len(balance) > 0
    assert list(balance.columns[:2]) == ["t_s", "mass_kg"]
    assert balance["t_s"].is_monotonic_increasing
    assert "angular_speed_rad_s" in session.readings["rotor_tach"].columns
    assert sorted(session.readings) == ["balance", "rotor_tach"]


def test_events_and_meta(sweep: Path) -> None:
    session = labkit.load_session(sweep)
    events = session.events
    assert list(events.columns[:2]) == ["t_s", "type"]
    assert (events["type"] == "point").sum() == 5
    assert session.meta["protocol"] == "speed-sweep" == session.protocol
    assert session.fit is not None and session.fit["model"] == "power-law"


def test_an_unknown_role_names_the_known_ones(sweep: Path) -> None:
    with pytest.raises(KeyError, match="roles: balance, rotor_tach"):
        labkit.load_session(sweep).readings["scale"]


def test_not_a_session_is_one_session_error(tmp_path: Path) -> None:
    with pytest.raises(labkit.SessionError, match="not a labkit session"):
        labkit.load_session(tmp_path)


def test_fit_data_gives_the_fit_of_labkit_fit(sweep: Path) -> None:
    report = labkit.fit_data(sweep, "power-law")
    b = report.to_json()["series"]["all"]["params"]["b"]["value"]
    # the emulated rig's model plant (docs/explanation/twin.md): the force of its magnets falls as about
    # rpm^-2.0
    assert b == pytest.approx(-2.0, abs=0.05)


def test_a_session_cut_short_gives_the_points_it_measured(sweep: Path, tmp_path: Path) -> None:
    """No results.json (a crash before the end): the points come from the point events."""
    import shutil

    cut = tmp_path / "cut"
    shutil.copytree(sweep, cut)
    (cut / "results.json").unlink()
    events = (cut / "events.jsonl").read_text().splitlines(keepends=True)
    third_point = [i for i, line in enumerate(events) if '"type":"point"' in line.replace(" ", "")][2]
    (cut / "events.jsonl").write_text("".join(events[: third_point + 1]) + '{"type": "poi')  # torn line
    session = labkit.load_session(cut)
    assert len(session.points) == 3
    assert session.fit is None
    assert session.problems == []  # a torn last line is a crash, not damage
