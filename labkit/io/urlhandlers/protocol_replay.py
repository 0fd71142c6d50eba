"""``replay://<cassette>?mode=strict|timed``: serve a recorded cassette as a port."""

from labkit.io.replay_port import serial_class_for_url

__all__ = ["serial_class_for_url"]
