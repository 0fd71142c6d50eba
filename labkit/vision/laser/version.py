"""The laser-trace analysis's version and stated accuracy (:mod:`labkit.vision.shared.versions`;
docs/explanation/replay.md#analysis-versions). Bump :data:`LASER_ANALYSIS`'s version whenever
:func:`labkit.vision.laser.analyse.analyse_laser` may give other answers for the same frames;
the accuracy is what its answers are held to across versions (checked on the bench's truth and
the robustness suite: docs/explanation/vision-throughput.md)."""

from __future__ import annotations

from labkit.vision.shared.versions import Accuracy, AnalysisVersion

#: 1: the first (every session recorded before versions); 2: the wander's refits and the ellipse's
#: band polish start from the fit's drift and stop once the curve settles (ADR 0039, ADR 0040);
#: 3: the wander's rounds stop once a round moves the chunk offsets by < 0.05 px (ADR 0043)
LASER_ANALYSIS = AnalysisVersion("laser", 3, {
    "tilt": Accuracy("1 %", rel=0.01),                          # cone angle, tilt of each semi-axis
    "tilt_stderr": Accuracy("1 % of the tilt", rel=0.01, of_other=True),  # odd/even halves apart
    "centre": Accuracy("0.5 px", abs=0.5),
    "semi_axes": Accuracy("1 % or 0.5 px", rel=0.01, abs=0.5),
    "verdict": Accuracy("equal"),
    "type": Accuracy("equal"),                                  # ellipse, circle, rosette, ...
    "loops": Accuracy("equal"),
    "reasons": Accuracy("the same words, numbers aside", words_only=True),
})
