"""spin-critical: the operator's Enter key registers a drop (real clock, stdin a terminal).

The key is read from stdin only when it is a TTY; a pseudo-terminal gives the run a real
one, and the test types Enter on its master side while a held floator is being watched.
"""

import os
import sys
import threading
from pathlib import Path

import pytest

from labkit.emulators.plant import shared_plant
from labkit.protocols.launch import execute, prepare_run
from labkit.protocols.operator import discard_pending_keys, operator_pressed_enter

RIGS = Path(__file__).resolve().parents[2] / "rigs"


class Operator:
    """Presses Enter every 0.5 s once the rotor has settled (a sink sees the events)."""

    def __init__(self, master: int) -> None:
        self.master, self.settled, self.stop = master, threading.Event(), threading.Event()
        self.spins_at_press: list[float] = []

    def on_event(self, event: dict) -> None:
        if event["type"] == "settled":
            self.settled.set()

    def run(self) -> None:
        self.settled.wait(timeout=60)
        while not self.stop.wait(0.5):
            self.spins_at_press.append(shared_plant("model-fig618").floator.spin_rad_s)
            os.write(self.master, b"\n")


def test_a_key_typed_before_the_trial_is_ignored(tmp_path, monkeypatch):
    master, slave = os.openpty()
    terminal = os.fdopen(slave, "r", buffering=1)
    monkeypatch.setattr(sys, "stdin", terminal)
    os.write(master, b"\n\n")             # typed while nothing was being watched
    try:
        discard_pending_keys()
        assert not operator_pressed_enter()
        os.write(master, b"\n")
        assert operator_pressed_enter()
        assert not operator_pressed_enter()
    finally:
        terminal.close()
        os.close(master)


def test_enter_on_the_terminal_registers_the_drop(tmp_path, monkeypatch):
    master, slave = os.openpty()
    terminal = os.fdopen(slave, "r", buffering=1)
    monkeypatch.setattr(sys, "stdin", terminal)
    # 9000 RPM: the plant would drop the floator only after ~7 s of spin-up, so the key comes first
    operator = Operator(master)
    # a loaded CI box may starve the in-process emulators: generous device timeouts (the test
    # is about the key, not about the tachometer's silence interlock)
    rig = tmp_path / "fig618.toml"
    rig.write_text((RIGS / "emulated-fig618.toml").read_text()
                   .replace("command_timeout_ms=500", "command_timeout_ms=0")
                   .replace("options = { command_timeout_ms = 500 }", "options = { reply_timeout_s = 2.0 }")
                   .replace("tach_timeout_s = 0.5", "tach_timeout_s = 5.0"))
    prep = prepare_run(rig, "spin-critical",
                       ["start_rpm=9000", "stop_rpm=9000", "max_trials=1"], clock="real",
                       session_root=tmp_path, sinks=[operator])
    typing = threading.Thread(target=operator.run, daemon=True)
    typing.start()
    try:
        outcome = execute(prep, tmp_path)
    finally:
        operator.stop.set()
        operator.settled.set()
        typing.join(timeout=5)
        terminal.close()
        os.close(master)
    assert outcome.status == "completed", outcome.reason
    assert operator.spins_at_press, "Enter was never pressed"
    [point] = outcome.results["points"]
    [trial] = point["trials"]
    assert trial["cause"] == "key"
    assert shared_plant("model-fig618").floator.drops == 0        # the plant itself never dropped it
    # the pair is the spin when Enter was pressed (the floator spins up ~100 rad/s per s):
    # the first press after the trial began, not one typed while the rotor settled
    assert any(abs(trial["spin_rad_s"] - spin) < 30.0 for spin in operator.spins_at_press)
    assert point["rotor_rpm"] == pytest.approx(9000, rel=0.02)


class ScriptedHand:
    """Signals the runner's operator every 0.5 s (clock) once the rotor settled, noting the
    floator's spin at each signal, like the terminal test's operator; a virtual-clock run, no
    terminal. Signals given before the trial began are discarded by the protocol."""

    def __init__(self, operator) -> None:
        self.operator, self.settled, self.last = operator, False, -1e9
        self.spins_at_signal: list[float] = []

    def on_event(self, event) -> None:
        if event.type == "settled":
            self.settled = True
        elif event.type == "reading" and self.settled and event.t - self.last >= 0.5:
            self.last = event.t
            self.spins_at_signal.append(shared_plant("model-fig618").floator.spin_rad_s)
            self.operator.signal()


def test_operator_signal_is_a_runner_verb_any_input_can_drive(tmp_path):
    from labkit.protocols.operator import QueuedOperator

    operator = QueuedOperator()
    hand = ScriptedHand(operator)
    prep = prepare_run(RIGS / "emulated-fig618.toml", "spin-critical",
                       ["start_rpm=9000", "stop_rpm=9000", "max_trials=1"], clock="virtual",
                       session_root=tmp_path, sinks=[hand])
    prep.runner.operator = operator
    outcome = execute(prep, tmp_path)
    assert outcome.status == "completed", outcome.reason
    [point] = outcome.results["points"]
    [trial] = point["trials"]
    assert trial["cause"] == "key"
    assert shared_plant("model-fig618").floator.drops == 0
    assert any(abs(trial["spin_rad_s"] - spin) < 30.0 for spin in hand.spins_at_signal)
