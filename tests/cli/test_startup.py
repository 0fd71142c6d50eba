"""Start-up: building a parser and printing ``--help`` imports none of the heavy libraries.

Every ``labkit CMD --help`` runs in a fresh interpreter (``python -m labkit``) that reports which
modules it ended up with; a command that imports scipy, numba, matplotlib, OpenCV or rerun while
building its parser fails here by name, without timing anything (issue 15: help under 0.3 s).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import pytest

from labkit.cli import COMMANDS
from labkit.cli.bench import BENCHES
from labkit.cli.summaries import COMMAND_SUMMARIES

HEAVY = ("scipy", "numba", "matplotlib", "cv2", "rerun", "PIL", "numpy")

PROBE = f"""
import json, sys
from labkit.cli import main
try:
    code = main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
print("\\n@@MODULES@@" + json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in {set(HEAVY)!r})))
sys.exit(code or 0)
"""

ARGVS = [["--help"]] + [[c, "--help"] for c in COMMANDS] + [["bench", b, "--help"] for b in BENCHES] + [
    ["analyse", "laser", "--help"], ["analyse", "strobe", "--help"],
    ["synth", "laser", "--help"], ["synth", "strobe", "--help"],
]


def run_help(argv: list[str]) -> tuple[str, list[str]]:
    proc = subprocess.run([sys.executable, "-c", PROBE, *argv], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    text, _, modules = proc.stdout.rpartition("\n@@MODULES@@")
    return text, json.loads(modules)


@pytest.mark.parametrize("argv", ARGVS, ids=lambda a: " ".join(a))
def test_help_imports_no_heavy_library(argv):
    text, modules = run_help(argv)
    assert "usage: labkit" in text
    assert modules == [], f"`labkit {' '.join(argv)}` imported {modules} while building its parser"


def test_top_level_help_imports_no_command_module_and_lists_every_command():
    """``labkit --help`` (and ``labkit`` alone) build their list from labkit.cli.summaries: no command
    module, no protocol, device or vision code is imported (it cost ~0.3 s of one core)."""
    probe = PROBE.replace("m.split(\".\")[0] in", "m.startswith(\"labkit.\") or m.split(\".\")[0] in")
    proc = subprocess.run([sys.executable, "-c", probe, "--help"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    text, _, modules = proc.stdout.rpartition("\n@@MODULES@@")
    loaded = set(json.loads(modules))
    commands = {f"labkit.cli.{c}" for c in COMMANDS} | {"labkit.protocols", "labkit.devices", "labkit.vision"}
    assert not loaded & commands, f"`labkit --help` imported {sorted(loaded & commands)}"
    flat = " ".join(text.split())
    for name, summary in COMMAND_SUMMARIES.items():
        assert f"{name} {' '.join(summary.split())}" in flat


def test_every_command_registers_its_summary():
    """The full parser (each command module's own ``register``) shows the same one line."""
    from labkit.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert {choice.dest: choice.help for choice in sub._choices_actions} == COMMAND_SUMMARIES


def test_the_probe_sees_a_heavy_import():
    """The check above can fail: a command that runs (not just --help) loads numba."""
    proc = subprocess.run([sys.executable, "-c", PROBE, "simulate", "--compile-only", "conical_5_1"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    modules = json.loads(proc.stdout.rpartition("\n@@MODULES@@")[2])
    assert "numba" in modules


def test_parser_names_match_their_registries():
    """The names parsers offer without importing their registries (labkit/cli/names.py)."""
    from labkit.cli import names
    from labkit.fit.models import MODELS, PAPER_OMEGA_C

    assert names.FIT_MODELS == tuple(MODELS)
    assert names.PAPER_OMEGA_C == PAPER_OMEGA_C


LASER_FIRST_FRAME = """
import json, sys
from labkit.vision.laser.analyse import analyse_laser
seen = []
def on_frame(index, t_s, bgr):
    if not seen:
        seen.append(sorted(m for m in sys.modules if m.split(".")[0] in ("scipy", "pykdtree")))
result = analyse_laser(sys.argv[1], on_frame=on_frame)
after = sorted(m for m in sys.modules if m.split(".")[0] in ("scipy", "pykdtree"))
print(json.dumps({"at_first_frame": seen[0], "after": after, "pattern": result.pattern.type}))
"""


def test_analyse_laser_reaches_its_first_frame_before_scipy():
    """Issue 15: ``analyse laser`` starts decoding at once and never imports scipy (about 0.3 s):
    its nearest-point queries use pykdtree (labkit.vision.laser.nearest), loaded only for the fit,
    while later frames decode. The second assertion shows the probe can see that load."""
    clip = Path(__file__).resolve().parents[2] / "recordings" / "videos" / "laser-ellipse-medium.mp4"
    proc = subprocess.run([sys.executable, "-c", LASER_FIRST_FRAME, str(clip)], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    seen = json.loads(proc.stdout.strip().splitlines()[-1])
    assert seen["at_first_frame"] == [], f"loaded before the first frame: {seen['at_first_frame']}"
    assert "pykdtree.kdtree" in seen["after"] and seen["pattern"] == "ellipse"
    assert not [m for m in seen["after"] if m.startswith("scipy")], seen["after"]


END_PROBE = """
import gc, sys
from labkit.cli import main
sys.argv = ["labkit", "rig", "--help"]
try:
    main() if {program} else main(["rig", "--help"])
except SystemExit:
    pass
print("@@FROZEN@@", gc.get_freeze_count())
"""


@pytest.mark.parametrize("program", [True, False])
def test_only_the_program_itself_ends_quickly(program):
    """``labkit ...`` freezes the garbage collector before the interpreter exits (``end_quickly``);
    ``main(argv)`` called inside another process (tests, notebooks) leaves it alone."""
    proc = subprocess.run([sys.executable, "-c", END_PROBE.format(program=program)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    frozen = int(proc.stdout.rpartition("@@FROZEN@@")[2])
    assert (frozen > 0) == program, frozen
