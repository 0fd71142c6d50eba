"""labkit.vision: laser-trace and stroboscope video analysis with OpenCV (issue 6).

Frame source -> detections -> trace -> pattern fit, pure functions where possible; no devices, no
rerun (live streams hook in through ``on_frame`` callbacks, see ``labkit.stream.vision``).

* :mod:`~labkit.vision.shared.frames`: videos and photos, with :class:`labkit.errors.VideoError` reasons
* :mod:`~labkit.vision.laser.trace`: laser light -> centre-line trace points; per-frame spot detection
* :mod:`~labkit.vision.shared.curves`: circle, ellipse and the trochoids of Eq. 6.38
  (``c + A e^{it} + B e^{ikt}``)
* :mod:`~labkit.vision.laser.pattern_fit`: geometric fits with drift and classification
* :mod:`~labkit.vision.laser.analyse`: ``analyse_laser`` (the ``labkit analyse laser`` JSON)
* :mod:`~labkit.vision.strobe.analyse`: ``analyse_strobe`` (tilt, lateral amplitude, RC offset, Eq. 5.97)

The public face (imported on first use, so ``import labkit.vision`` does not load OpenCV):
:func:`analyse_laser`, :func:`analyse_strobe`, :func:`open_frames`, :class:`Pattern`.
"""

from labkit.lazy import lazy_attributes

_PUBLIC = {"analyse_laser": "labkit.vision.laser.analyse", "analyse_strobe": "labkit.vision.strobe.analyse",
           "open_frames": "labkit.vision.shared.frames", "Pattern": "labkit.vision.shared.curves"}

__all__ = sorted(_PUBLIC)


__getattr__ = lazy_attributes(__name__, _PUBLIC)
