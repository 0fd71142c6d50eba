"""Deprecated: the balance drivers live in :mod:`labkit.devices.balance`
(docs/decisions/0035-one-name-per-thing.md).

``import labkit.devices.loadcell.mtsics`` (and ``and_std``, ``line_regex``, ``continuous``,
``units``, now :mod:`labkit.units`) still works for a plugin written against the old package name, with a
DeprecationWarning; the modules are the same objects as under ``labkit.devices.balance``.
"""

from __future__ import annotations

import sys
import warnings

from labkit import units
from labkit.devices.balance import and_std, continuous, line_regex, mtsics

warnings.warn("labkit.devices.loadcell is labkit.devices.balance now; the old name is an alias "
              "that will go", DeprecationWarning, stacklevel=2)

for _module in (and_std, continuous, line_regex, mtsics, units):
    sys.modules[f"{__name__}.{_module.__name__.rpartition('.')[2]}"] = _module   # units: labkit.units

__all__ = ["and_std", "continuous", "line_regex", "mtsics", "units"]
