"""The strobe analysis's version and stated accuracy (:mod:`labkit.vision.shared.versions`;
docs/explanation/replay.md#analysis-versions). Bump :data:`STROBE_ANALYSIS`'s version whenever
:func:`labkit.vision.strobe.analyse.analyse_strobe` may give other answers for the same frames.
The accuracy is the one the analysis-only level already holds a strobe-sweep's points to
(phi, beta, delta 0.5 %, their standard errors a factor of 3)."""

from __future__ import annotations

from labkit.vision.shared.versions import Accuracy, AnalysisVersion

#: 1: the first; 2: a room-light correction that does not hold for the whole clip (the tilt on the
#: frames it was fitted on and on all frames more than 10 % apart) makes the verdict doubtful
STROBE_ANALYSIS = AnalysisVersion("strobe", 2, {
    "phi": Accuracy("0.5 %", rel=0.005),
    "beta": Accuracy("0.5 %", rel=0.005),
    "delta": Accuracy("0.5 %", rel=0.005),
    "apparent_hz": Accuracy("0.5 %", rel=0.005),
    "stderr": Accuracy("a factor of 3", rel=2 / 3),
    "verdict": Accuracy("equal"),
    "reasons": Accuracy("the same words, numbers aside", words_only=True),
})
