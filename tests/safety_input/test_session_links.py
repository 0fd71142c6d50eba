"""A session from elsewhere whose output files are symbolic links (issue 27): `labkit report`
and `labkit replay --export-csv` refuse before writing, and the link's target is untouched."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from labkit.cli import main

CLEAN = Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "speed-sweep-clean"


@pytest.fixture
def downloaded(tmp_path):
    session = tmp_path / "downloaded"
    shutil.copytree(CLEAN, session)
    victim = tmp_path / "home-file.txt"
    victim.write_text("precious\n")
    return session, victim


@pytest.mark.parametrize("link", ["report", "report/report.md", "report/fig-power-law.png"])
def test_report_writes_nothing_through_a_link(downloaded, capsys, link):
    session, victim = downloaded
    target = victim if link != "report" else victim.parent / "elsewhere"
    target.mkdir(exist_ok=True) if link == "report" else None
    (session / link).parent.mkdir(exist_ok=True)
    (session / link).symlink_to(target)
    assert main(["report", str(session)]) != 0
    err = capsys.readouterr().err
    assert "symbolic link" in err or "leads outside the session" in err, err
    assert "Traceback" not in err
    assert victim.read_text() == "precious\n"
    if link == "report":
        assert list(target.iterdir()) == []


def test_export_csv_writes_nothing_through_a_link(downloaded, capsys):
    session, victim = downloaded
    (session / "readings" / "balance.csv").symlink_to(victim)
    assert main(["replay", str(session), "--export-csv"]) != 0
    err = capsys.readouterr().err
    assert "symbolic link" in err or "leads outside the session" in err, err
    assert victim.read_text() == "precious\n"


def test_a_clean_copy_still_reports_and_exports(downloaded):
    session, _ = downloaded
    assert main(["report", str(session)]) == 0
    assert main(["replay", str(session), "--export-csv"]) == 0
    assert (session / "readings" / "balance.csv").is_file()


def test_a_cassette_that_is_a_device_is_refused_without_reading_it(downloaded, capsys):
    session, _ = downloaded
    cassette = session / "cassettes" / "balance.jsonl"
    cassette.unlink()
    cassette.symlink_to("/dev/zero")
    assert main(["replay", str(session)]) != 0
    err = capsys.readouterr().err
    assert "not a regular file" in err and "Traceback" not in err, err
