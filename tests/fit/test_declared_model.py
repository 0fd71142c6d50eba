"""``labkit fit SESSION`` without --model fits the model the session's protocol declares (issue 27)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from labkit.cli import main

SESSIONS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"


@pytest.mark.parametrize(("session", "model"), [("speed-sweep-clean", "power-law"),
                                                ("spin-critical-clean", "spin-critical")])
def test_the_session_says_which_model(tmp_path, capsys, session, model):
    out = tmp_path / "fit.json"
    assert main(["fit", str(SESSIONS / session), "--json", str(out)]) == 0
    assert f"model {model} (the one this session's protocol declares)" in capsys.readouterr().err
    declared = json.loads(out.read_text())
    assert main(["fit", str(SESSIONS / session), "--model", model, "--json", str(tmp_path / "b.json")]) == 0
    assert declared == json.loads((tmp_path / "b.json").read_text())


def test_a_table_that_does_not_say_is_refused_with_the_models(tmp_path, capsys):
    csv = tmp_path / "x.csv"
    csv.write_text("a,b\n1,2\n2,3\n")
    assert main(["fit", str(csv)]) == 2
    err = capsys.readouterr().err
    assert "does not say which model fits it" in err and "power-law" in err and "Traceback" not in err
