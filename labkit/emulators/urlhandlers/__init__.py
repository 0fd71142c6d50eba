"""pyserial URL handlers of the emulators (``sim://``), found through
``serial.protocol_handler_packages``; importing :mod:`labkit.emulators` adds this package."""
