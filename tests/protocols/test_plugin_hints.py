"""A protocol from another package, installed through its entry point, gets a live figure, a
live fit and a report figure from the hints it declares, with no line of labkit naming it
(ADR 0021, docs/how-to/add-a-protocol.md). The package is a real dist-info directory on PYTHONPATH, so
importlib.metadata finds it as it finds a pip-installed one; the run is ``labkit run`` on the
emulated Fig. 5.25 rig in its own process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from labkit.stream.readback import column, entity_paths

WORKTREE = Path(__file__).resolve().parents[2]

#: the example in docs/how-to/add-a-protocol.md, word for word (the test reads it from there)
DOC = WORKTREE / "docs" / "how-to" / "add-a-protocol.md"


def plugin_source() -> str:
    """The ``thrust_plugin`` module of docs/how-to/add-a-protocol.md (the python block after its marker)."""
    text = DOC.read_text()
    start = text.index("<!-- thrust_plugin.py -->")
    block = text[text.index("```python\n", start) + len("```python\n"):]
    return block[: block.index("```")]


def install(site: Path) -> None:
    (site / "thrust_plugin").mkdir(parents=True)
    (site / "thrust_plugin" / "__init__.py").write_text(plugin_source())
    info = site / "thrust_plugin-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: thrust-plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[labkit.protocols]\nthrust-sweep = thrust_plugin:ThrustSweep\n")


def labkit(args: list[str], cwd: Path, site: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(WORKTREE), str(site)]))
    return subprocess.run([sys.executable, "-m", "labkit", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def plugin_run(tmp_path_factory) -> tuple[Path, Path, Path]:
    """``(session, run.rrd, report folder)`` of one run of the plugin's protocol."""
    tmp = tmp_path_factory.mktemp("plugin")
    site = tmp / "site"
    install(site)
    rrd = tmp / "run.rrd"
    done = labkit(["run", str(WORKTREE / "rigs" / "emulated-fig525.toml"), "thrust-sweep", "--sessions", "s",
                   "--no-progress", "--rerun", f"save:{rrd}", "--json", "-"], tmp, site)
    assert done.returncode == 0, done.stderr
    outcome = json.loads(done.stdout)
    assert outcome["status"] == "completed", outcome
    session = tmp / outcome["session"]
    report = labkit(["report", str(session), "--out", str(tmp / "report")], tmp, site)
    assert report.returncode == 0, report.stderr
    return session, rrd, tmp / "report"


def test_the_start_document_carries_what_the_plugin_declares(plugin_run):
    session, _, _ = plugin_run
    start = json.loads((session / "events.jsonl").read_text().splitlines()[0])
    assert start["protocol"] == "thrust-sweep"
    assert start["hints"]["x"] == "speed_rad_s" and start["hints"]["y"] == "thrust_mn"
    assert {c["name"]: c["unit"] for c in start["row"]} == {"step": "", "speed_rad_s": "rad/s",
                                                            "thrust_mn": "mN"}
    specs = {p["name"]: p for p in start["param_specs"]}
    record = specs["record_s"]
    assert record["unit"] == "s" and (record["low"], record["high"]) == (0.5, 10)
    points = json.loads((session / "results.json").read_text())["points"]
    assert all(set(p) == {"step", "speed_rad_s", "thrust_mn"} for p in points)


def test_the_live_view_draws_the_plugins_figure_and_fit(plugin_run):
    session, rrd, _ = plugin_run
    points = json.loads((session / "results.json").read_text())["points"]
    n = len(points)
    entities = entity_paths(rrd)
    assert {"/thrust_curve/plot/data", "/thrust_curve/residual/after_04", "/events"} <= entities
    assert {e for e in entities if e.startswith("/thrust_curve/plot/fit/")} == \
        {f"/thrust_curve/plot/fit/after_{k:02d}" for k in range(3, n + 1)}
    assert not any(e.startswith(("/fig5_25", "/fig6_18")) for e in entities)
    x, y = column(rrd, "/thrust_curve/plot/data", "Scalars:scalars", "rotor speed [rad/s]")
    assert x == [round(p["speed_rad_s"]) for p in points]
    assert np.allclose([v[0] for v in y], [p["thrust_mn"] for p in points], rtol=1e-9)


def test_the_report_fits_and_draws_what_the_hints_declare_as_the_live_view_did(plugin_run):
    session, rrd, report = plugin_run
    text = (report / "report.md").read_text()
    assert "### power-law fit: thrust [mN] against rotor speed [rad/s]" in text
    assert "(fig-power-law.png)" in text and (report / "fig-power-law.png").stat().st_size > 10_000
    fit = json.loads((report / "fits.json").read_text())["power-law"]["series"]["all"]
    a, b = fit["params"]["a"]["value"], fit["params"]["b"]["value"]
    assert b < 0   # the PFR force falls with speed (Eq. 5.81), on the emulated rig as in Fig. 5.25
    # the live fit after the last point is the report's fit: the same curve to 1e-6
    n = len(json.loads((session / "results.json").read_text())["points"])
    grid, curve = column(rrd, f"/thrust_curve/plot/fit/after_{n:02d}", "Scalars:scalars",
                         "rotor speed [rad/s]")
    live = np.array([c[0] for c in curve])
    assert np.allclose(live, a * np.asarray(grid, float) ** b, rtol=1e-6)
