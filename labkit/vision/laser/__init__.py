"""The laser-trace pipeline (ADR 0034): ``analyse`` reads the frames into accumulated chunks,
``frame_path`` and ``trace`` turn the light into trace points, ``gather`` collects them,
``pattern`` fits and classifies them (``pattern_fit``, ``starts``, ``wander``, ``loops_seen``,
``stray_light``, ``second_reading``), ``checks`` and ``scene_kind`` judge the fit, ``overlay``
draws it and ``result`` holds it. The face, imported on first use: :func:`analyse_laser`,
:class:`LaserResult`."""

from labkit.lazy import lazy_attributes

_PUBLIC = {"analyse_laser": "labkit.vision.laser.analyse", "LaserResult": "labkit.vision.laser.result"}

__all__ = sorted(_PUBLIC)


__getattr__ = lazy_attributes(__name__, _PUBLIC)
