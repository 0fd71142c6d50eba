"""Reports and fits read the floator's inertia through labkit.rig, in any unit a rig file allows."""

import shutil

import pytest

from labkit.report.build import floator_inertia

SESSION = "recordings/sessions/spin-critical-clean"


def _session_with_rig(tmp_path, rig_text):
    session = tmp_path / "session"
    shutil.copytree(SESSION, session)
    (session / "rig.toml").write_text(rig_text)
    return session


def test_inertia_in_g_mm2_is_converted(tmp_path):
    text = open(f"{SESSION}/rig.toml").read()
    assert "inertia_radial_kg_m2 = 3e-7" in text
    text = text.replace("inertia_radial_kg_m2 = 3e-7", "inertia_radial_g_mm2 = 300")
    assert floator_inertia(_session_with_rig(tmp_path, text)) == pytest.approx(3e-7)


def test_recorded_session_and_unreadable_rig(tmp_path):
    from pathlib import Path

    assert floator_inertia(Path(SESSION)) == pytest.approx(3e-7)
    assert floator_inertia(_session_with_rig(tmp_path, "this is = = not toml")) is None
