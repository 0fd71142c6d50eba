"""The older word for a device kind still loads (docs/decisions/0035-one-name-per-thing.md):
``kind = "tach"`` in a rig file, in the rig copies of recorded sessions, in a protocol's
``needs``, in ``driver_class`` and in ``labkit probe``; each is read as ``tachometer``."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.cli import main
from labkit.device_kinds import DEVICE_KINDS, OLD_KIND_WORDS, canonical_kind
from labkit.devices.base import Tachometer
from labkit.devices.registry import driver_class, known_drivers
from labkit.errors import RigFileError
from labkit.rig import load_rig, parse_rig

REPO = Path(__file__).resolve().parents[2]
RECORDED_RIGS = sorted((REPO / "recordings" / "sessions").glob("*/rig.toml"))
OLD = """
[rig]
name = "old-words"
[devices.rotor_motor]
kind = "motor"
protocol = "pololu_smc"
port = "sim://pololu_smc?plant=t"
[devices.rotor_tach]
kind = "tach"
protocol = "labkit_tach"
port = "sim://labkit_tach?plant=t"
[limits]
max_speed_rpm = 12000
max_ramp_rpm_per_s = 3000
"""


def test_every_old_word_names_a_kind_and_no_kind_is_renamed_to_itself():
    assert set(OLD_KIND_WORDS.values()) <= set(DEVICE_KINDS)
    assert not set(OLD_KIND_WORDS) & set(DEVICE_KINDS)
    assert [canonical_kind(k) for k in DEVICE_KINDS] == list(DEVICE_KINDS)


def test_a_rig_file_saying_tach_loads_as_a_tachometer_and_pairs_its_loop():
    rig = parse_rig(OLD)
    assert rig.devices["rotor_tach"].kind == "tachometer"
    assert [(lc.motor, lc.tach) for lc in rig.control.loops] == [("rotor_motor", "rotor_tach")]
    assert rig.require("rotor_tach", "tach", "an old protocol") is rig.devices["rotor_tach"]
    assert rig.require("rotor_tach", "tachometer", "speed-sweep") is rig.devices["rotor_tach"]
    assert set(rig.devices_of("tach")) == set(rig.devices_of("tachometer")) == {"rotor_tach"}


def test_a_wrong_kind_names_the_kinds_and_the_old_word():
    with pytest.raises(RigFileError, match=r"devices.rotor_tach.kind.*tachometer.*'tach' for 'tachometer'"):
        parse_rig(OLD.replace('kind = "tach"', 'kind = "tacho"'))


@pytest.mark.parametrize("path", RECORDED_RIGS, ids=[p.parent.name for p in RECORDED_RIGS])
def test_the_rig_copies_of_recorded_sessions_still_load(path):
    text = path.read_text()
    rig = load_rig(path)
    if 'kind = "tach"' in text:
        assert any(d.kind == "tachometer" for d in rig.devices.values())
    assert {d.kind for d in rig.devices.values()} <= set(DEVICE_KINDS)


def test_some_recorded_session_still_says_tach():
    # the alias is exercised by the recordings themselves, not only by the text above
    assert any('kind = "tach"' in p.read_text() for p in RECORDED_RIGS)


def test_driver_lookup_and_the_list_of_drivers_use_the_one_word():
    assert driver_class("tach", "labkit_tach") is driver_class("tachometer", "labkit_tach")
    assert issubclass(driver_class("tach", "lutron16"), Tachometer)
    assert "tach" not in known_drivers() and "labkit_tach" in known_drivers()["tachometer"]


def test_probe_accepts_the_old_word(capsys):
    code = main(["probe", "tach", "--protocol", "labkit_tach", "--port", "sim://labkit_tach?seed=1",
                 "--samples", "1"])
    out = capsys.readouterr().out.splitlines()
    assert code == 0 and out[0].startswith('# {"device": "tachometer labkit_tach at ')
    assert '"quantity": "angular_speed"' in out[1]


class _EntryPoint:
    """What importlib.metadata gives for one entry point (the stdlib, stood in for)."""

    group, name, value, dist = "labkit.drivers", "old-tach", "oldlab:OldTach", None

    def __init__(self, obj):
        self.obj = obj

    def load(self):
        return self.obj


def test_a_plugin_driver_saying_tach_is_registered_as_a_tachometer(monkeypatch):
    import labkit.plugins as plugins
    from labkit.devices.base import Device

    class OldTach(driver_class("tachometer", "labkit_tach")):
        kind = "tach"
        protocol = "old_word_tach"

    monkeypatch.setattr(plugins, "entry_points", lambda group: [_EntryPoint(OldTach)] if
                        group == plugins.DRIVER_GROUP else [])
    monkeypatch.setattr(plugins, "_loaded", set())
    registry: dict = {}
    plugins.load_driver_plugins(registry, Device)
    assert registry == {("tachometer", "old_word_tach"): OldTach}
