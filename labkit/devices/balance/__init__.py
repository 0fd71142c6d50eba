"""Balance and load-cell drivers (docs/reference/devices-balance.md): importing this registers them.

* :mod:`.mtsics`: Mettler Toledo MT-SICS (and the labkit HX711 sketch).
* :mod:`.and_std`: A&D standard format (2400 7E1, ``N`` unit for force).
* :mod:`.line_regex`: third-party HX711 + Arduino sketches (presets, configurable regex).
"""

from labkit.devices.balance import and_std, line_regex, mtsics  # noqa: F401
