"""labkit.emulators: byte-level stand-ins for the devices, on seeded plants (docs/reference/io.md).

Importing this package registers the ``sim://`` URL handler with pyserial
(``serial.protocol_handler_packages``), so :func:`labkit.io.open_port` opens
``sim://mtsics?plant=fig525`` ports; the transport itself knows no emulator
(docs/decisions/0005-emulators-own-sim-urls.md).

* :class:`Emulation`, :func:`use_emulation`, :func:`current_emulation` - the plants of one
  emulated rig, scoped (docs/decisions/0006-scoped-emulations.md);
* :func:`build_emulator` - the emulator a ``sim://`` URL describes;
* :func:`emulator_class`, :func:`register_emulator`, :class:`Emulator` - the registry;
* :class:`RigPlant` - the physics the emulators share; :func:`parse_sim_url`;
* ``sim://camera`` - :class:`labkit.emulators.camera.SimCameraSource`, the emulated camera
  (registered with :mod:`labkit.devices.camera` here).
"""

from labkit.devices.camera.device import register_camera_source
from labkit.emulators.base import Emulator, emulator_class, parse_faults, register_emulator
from labkit.emulators.camera import SimCameraSource
from labkit.emulators.plant import Emulation, current_emulation, shared_plant, use_emulation
from labkit.emulators.rig_plant import RigPlant
from labkit.emulators.sim_port import SimSerial, build_emulator
from labkit.emulators.urls import SimSpec, parse_sim_url
from labkit.io.ports import register_url_handlers

SIM_HANDLER_PACKAGE = "labkit.emulators.urlhandlers"
register_url_handlers(SIM_HANDLER_PACKAGE)
register_camera_source("sim", SimCameraSource)

__all__ = [
    "SIM_HANDLER_PACKAGE", "Emulation", "Emulator", "RigPlant", "SimSerial", "SimSpec", "build_emulator",
    "current_emulation", "emulator_class", "parse_faults", "parse_sim_url", "register_emulator",
    "shared_plant", "use_emulation",
]
