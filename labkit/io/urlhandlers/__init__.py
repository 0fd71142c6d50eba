"""pyserial URL handlers of labkit, found through ``serial.protocol_handler_packages``.

One module ``protocol_<scheme>`` per scheme, each exposing ``serial_class_for_url``.
:func:`labkit.io.ports.register_url_handlers` adds this package to pyserial's list.
"""
