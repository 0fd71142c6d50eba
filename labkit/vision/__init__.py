"""labkit.vision: laser-trace and stroboscope video analysis with OpenCV (issue 6), in three
packages named by pipeline stage (ADR 0034); no devices, no rerun (live streams hook in through
``on_frame`` callbacks, see ``labkit.stream.vision``).

* :mod:`~labkit.vision.shared`: frame sources (:mod:`~labkit.vision.shared.frames`, with
  :class:`labkit.errors.VideoError` reasons), the curves of Eq. 6.38
  (:mod:`~labkit.vision.shared.curves`, ``c + A e^{it} + B e^{ikt}``), the one verdict type
  (:mod:`~labkit.vision.shared.verdict`) and the typed results' base
* :mod:`~labkit.vision.laser`: frames -> trace points -> pattern fit -> checks;
  ``analyse_laser`` (the ``labkit analyse laser`` result, :class:`LaserResult`)
* :mod:`~labkit.vision.strobe`: frames -> body -> phase -> Eq. 5.97 fit -> checks;
  ``analyse_strobe`` (tilt, lateral amplitude, RC offset, :class:`StrobeResult`)

The public face (imported on first use, so ``import labkit.vision`` does not load OpenCV):
:func:`analyse_laser`, :func:`analyse_strobe`, :class:`LaserResult`, :class:`StrobeResult`,
:func:`open_frames`, :class:`Pattern`.
"""

from labkit.lazy import lazy_attributes

_PUBLIC = {"analyse_laser": "labkit.vision.laser.analyse", "analyse_strobe": "labkit.vision.strobe.analyse",
           "LaserResult": "labkit.vision.laser.result", "StrobeResult": "labkit.vision.strobe.result",
           "open_frames": "labkit.vision.shared.frames", "Pattern": "labkit.vision.shared.curves"}

__all__ = sorted(_PUBLIC)


__getattr__ = lazy_attributes(__name__, _PUBLIC)
