"""Old names of the balance kind still load (docs/decisions/0035-one-name-per-thing.md)."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import labkit.devices.balance.mtsics as mtsics


def test_the_loadcell_package_is_an_alias_of_balance_with_a_deprecation_warning():
    # a fresh interpreter: the warning fires once, when the alias is first imported
    code = ("import warnings; warnings.simplefilter('error')\n"
            "try:\n"
            "    import labkit.devices.loadcell.mtsics\n"
            "except DeprecationWarning as w:\n"
            "    print('warned:', w)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.startswith("warned: labkit.devices.loadcell is labkit.devices.balance")


def test_a_plugin_importing_the_old_module_gets_the_same_driver_class():
    with pytest.warns(DeprecationWarning, match="labkit.devices.balance"):
        sys.modules.pop("labkit.devices.loadcell", None)
        old = importlib.import_module("labkit.devices.loadcell")
    from labkit.devices.loadcell.mtsics import MtSicsBalance

    assert MtSicsBalance is mtsics.MtSicsBalance
    assert old.line_regex is importlib.import_module("labkit.devices.balance.line_regex")
