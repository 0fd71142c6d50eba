"""``record://<inner-url>?cassette=PATH&port=NAME``: tee a port's traffic into a cassette."""

from labkit.io.record_port import serial_class_for_url

__all__ = ["serial_class_for_url"]
