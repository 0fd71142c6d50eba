"""A misspelt rig key ends in one line that names the key it was probably meant to be."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.rig import parse_rig
from labkit.rig.checks import RigFileError

TEMPLATE = (Path(__file__).resolve().parents[2] / "rigs" / "template-balance.toml").read_text()


@pytest.mark.parametrize(("good", "bad", "message"), [
    ('port = "/dev/ttyACM0"', 'prot = "/dev/ttyACM0"',
     "devices.rotor_motor.port: missing (required); the file has 'prot': did you mean 'port'?"),
    ("max_speed_rpm = 20000", "max_sped_rpm = 20000",
     "limits.max_speed_rpm: missing (required); the file has 'max_sped_rpm': did you mean 'max_speed_rpm'?"),
    ("description =", "descripton =", "rig.descripton: unknown key; did you mean 'description'?"),
    ("kp = 2e-4", "kpp = 2e-4", "control.kpp: unknown key; did you mean 'kp'?"),
])
def test_a_misspelt_key_says_did_you_mean(good: str, bad: str, message: str) -> None:
    assert good in TEMPLATE
    with pytest.raises(RigFileError) as caught:
        parse_rig(TEMPLATE.replace(good, bad, 1), "my-rig.toml")
    assert str(caught.value).endswith(message), str(caught.value)
    assert "\n" not in str(caught.value)


def test_an_unrelated_key_gets_no_guess() -> None:
    with pytest.raises(RigFileError) as caught:
        parse_rig(TEMPLATE.replace("kp = 2e-4", "zzz = 2e-4", 1), "my-rig.toml")
    assert str(caught.value).endswith("control.zzz: unknown key")


def test_a_misspelt_protocol_and_parameter_say_did_you_mean(capsys) -> None:
    from labkit.cli import main

    assert main(["run", "emulated-fig525", "speed-swep", "--dry-run"]) == 2
    assert ("unknown protocol 'speed-swep' (did you mean 'speed-sweep'?); known: cone-sweep, speed-sweep, "
            "spin-critical") in capsys.readouterr().err
    assert main(["run", "emulated-fig525", "speed-sweep", "--set", "speed_rpm=6000", "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert "--set speed_rpm: unknown parameter of speed-sweep; did you mean 'speeds_rpm'?" in err
