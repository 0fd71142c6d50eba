"""The stroboscope pipeline (ADR 0034): ``analyse`` measures the ``body`` in every frame (with
``room_light`` and ``room_light_fit`` taking the room light out), maps frames to rotor phase
(``phase``), fits Eq. 5.97 (``motion_fit``, or the rolling shutter's ``rolling_model`` and
``rolling_analysis``), judges the fit (``checks``), draws it (``overlay``) and holds it
(``result``). The face, imported on first use: :func:`analyse_strobe`, :class:`StrobeResult`."""

from labkit.lazy import lazy_attributes

_PUBLIC = {"analyse_strobe": "labkit.vision.strobe.analyse", "StrobeResult": "labkit.vision.strobe.result"}

__all__ = sorted(_PUBLIC)


__getattr__ = lazy_attributes(__name__, _PUBLIC)
