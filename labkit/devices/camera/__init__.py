"""Cameras (kind ``camera``): a webcam over V4L2, a phone's MJPEG stream, the emulated camera,
frame cassettes (docs/reference/camera.md, docs/decisions/0023-camera-device.md).

* :func:`open_camera` - a :class:`Camera` from a port URL (:mod:`labkit.devices.camera.urls`);
* :class:`Frame`, :class:`CameraSettings` - what a camera delivers and what it accepted;
* :mod:`labkit.devices.camera.cassette` - frame cassettes (``record://``, ``replay://``).
"""

from labkit.devices.camera.device import Camera, open_camera
from labkit.devices.camera.frames import CameraSettings, Frame
from labkit.devices.camera.urls import CameraRequest, is_camera_url, parse_camera_url

__all__ = ["Camera", "CameraRequest", "CameraSettings", "Frame", "is_camera_url", "open_camera",
           "parse_camera_url"]
