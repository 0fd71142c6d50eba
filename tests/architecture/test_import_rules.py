"""Import rules inside labkit (issue 24, ADR 0028), read from the source (tests/architecture/
import_rules.py): no import cycle among a package's modules, imports inside functions counted
and those under ``if TYPE_CHECKING:`` not; no private name imported from another module; the
top-level parts import only downwards in an explicit layer order."""

from __future__ import annotations

from pathlib import Path

from .import_rules import import_cycles, layer_violations, private_imports

LABKIT = Path(__file__).resolve().parents[2] / "labkit"

# labkit's top-level parts from the bottom up (ADR 0028): a part imports parts of its own layer
# or of the layers below, never above; within a layer the parts stay free of cycles
# (test_import_graph.py).
LAYERS: list[set[str]] = [
    # 0. words every part may use: errors, units, ranges, the body table, presentation hints, the
    # one reading shape
    {"errors", "units", "ranges", "lazy", "bodies", "hints", "plugins", "readings", "device_kinds"},
    # 1. the transport, the physics and the image analysis: none knows a device or a rig
    {"io", "model", "sim", "vision"},
    # 2. the device drivers; predictions, synthetic footage and images built on the physics
    {"devices", "predict", "synth", "footage", "testing"},
    # 3. what a run writes, and the emulators that stand in for the devices
    {"documents", "session", "emulators"},
    # 4. what runs a device and what reads a run's data
    {"control", "fit", "stream"},
    # 5. a rig: its file, checked against drivers and emulators, and opened
    {"rig"},
    # 6. the protocols and the reports on their results
    {"protocols", "report"},
    # 7. whole runs reproduced: the digital twin, the paper's figures, the numerics studies
    {"twin", "reproduce", "numerics"},
    # 8. the command line
    {"cli", "__main__"},
]


def test_no_import_cycle_inside_a_package():
    found = import_cycles(LABKIT)
    assert not found, f"{len(found)} import cycles inside labkit's packages:\n  " + "\n  ".join(found)


def test_no_private_name_is_imported_across_modules():
    found = private_imports(LABKIT)
    assert not found, f"{len(found)} private names imported across modules:\n  " + "\n  ".join(found)


def test_the_top_level_parts_import_only_downwards():
    found = layer_violations(LABKIT, LAYERS)
    assert not found, "imports against the layer order:\n  " + "\n  ".join(found)
