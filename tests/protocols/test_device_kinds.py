"""The device kinds as typed protocols (labkit.devices.kinds): every built-in driver of a kind
satisfies its kind's protocol, a motor or a tachometer is no balance and a motor no tachometer,
so ``RunContext.balance`` / ``.tachometer`` / ``.camera`` refuse them (a streaming balance also
offers its readings as a tachometer does: structural, as intended)."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.devices.kinds import BalanceKind, CameraKind, TachometerKind
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import load_rig, open_rig

REPO = Path(__file__).resolve().parents[2]
KINDS = {"balance": BalanceKind, "tachometer": TachometerKind, "camera": CameraKind}


@pytest.mark.parametrize("rig_name", ["emulated-fig525", "emulated-fig618", "emulated-camera"])
def test_each_driver_satisfies_its_kinds_protocol(rig_name):
    rig = load_rig(REPO / "rigs" / f"{rig_name}.toml")
    clock = VirtualClock()
    seen = set()
    with use_clock(clock), open_rig(rig, clock) as opened:
        for role, driver in opened.drivers.items():
            kind = rig.devices[role].kind
            matches = {k for k, proto in KINDS.items() if isinstance(driver, proto)}
            if kind in KINDS:
                assert kind in matches, (role, kind, matches)
            if kind in ("tachometer", "motor", "strobe"):
                assert "balance" not in matches and "camera" not in matches, (role, kind, matches)
            if kind == "motor":
                assert matches == set(), (role, matches)
            seen.add(kind)
    assert seen & set(KINDS)
