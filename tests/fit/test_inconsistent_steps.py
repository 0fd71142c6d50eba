"""A spin-critical step whose trials did not agree (``consistent: false``) is left out of every
fit of the session, and said so (issue 27: kept in, it carried the largest residual)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.protocols import SpinCritical

CLEAN = Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "spin-critical-clean"


def _spoiled(tmp_path: Path) -> tuple[Path, list[dict]]:
    """The clean recording's points plus a fourth step whose spin is far off and inconsistent."""
    results = json.loads((CLEAN / "results.json").read_text())
    points = results["points"]
    bad = {**points[-1], "step": 3, "rotor_rad_s": 1000.0, "spin_rad_s": 400.0, "consistent": False}
    points.append(bad)
    out = tmp_path / "results.json"
    out.write_text(json.dumps({**results, "points": points}))
    return out, points


def test_the_quick_fit_leaves_the_inconsistent_step_out_and_names_it(tmp_path):
    _, points = _spoiled(tmp_path)
    proto = SpinCritical()
    clean = proto.fit(points[:3])
    spoiled = proto.fit(points)
    assert spoiled["left_out_steps"] == [3]
    assert spoiled["params"]["C"]["value"] == pytest.approx(clean["params"]["C"]["value"], rel=1e-12)
    assert "left_out_steps" not in clean


def test_labkit_fit_leaves_it_out_with_a_warning(tmp_path, capsys):
    path, _ = _spoiled(tmp_path)
    out = tmp_path / "fit.json"
    assert main(["fit", str(path), "--model", "spin-critical", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    series = json.loads(out.read_text())["series"]["all"]
    assert series["n"] == 3
    assert any("left out of the fit: step 3" in w for w in series["warnings"])
    assert "step 3" in text
    assert main(["fit", str(CLEAN / "results.json"), "--model", "spin-critical", "--json",
                 str(tmp_path / "clean.json")]) == 0
    clean = json.loads((tmp_path / "clean.json").read_text())["series"]["all"]
    assert series["params"]["C"]["value"] == pytest.approx(clean["params"]["C"]["value"], rel=1e-9)


def test_a_session_whose_steps_all_disagree_is_still_fitted(tmp_path):
    results = json.loads((CLEAN / "results.json").read_text())
    for p in results["points"]:
        p["consistent"] = False
    session = tmp_path / "session"
    shutil.copytree(CLEAN, session)
    (session / "results.json").write_text(json.dumps(results))
    assert main(["fit", str(session), "--model", "spin-critical", "--json", str(tmp_path / "f.json")]) == 0
    assert json.loads((tmp_path / "f.json").read_text())["series"]["all"]["n"] == 3
