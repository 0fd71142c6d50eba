"""Helpers for testing code that uses labkit, and for labkit's own tests.

* :func:`expected_protocol` - a driver against a strict list of byte pairs, in memory
  (:mod:`labkit.testing.protocol`);
* :func:`start_group` / :func:`stop_group` - child processes ended with their own children
  (:mod:`labkit.testing.processes`);
* :mod:`labkit.testing.strobe_cylinder` - strobe clips of a cylinder drawn with their own geometry
  (not ``labkit.footage``, not ``labkit.synth``), for checking and timing the strobe analysis
  (imported on its own: it needs OpenCV).
"""

from labkit.testing.processes import start_group, stop_group
from labkit.testing.protocol import ExchangePort, ProtocolMismatch, expected_protocol

__all__ = ["ExchangePort", "ProtocolMismatch", "expected_protocol", "start_group", "stop_group"]
