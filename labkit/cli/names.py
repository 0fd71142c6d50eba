"""Names the command parsers offer before any work starts, kept free of heavy imports.

Building a parser (``labkit CMD --help``) must not import scipy, numba, matplotlib, OpenCV or
rerun; the registries these names come from import them. ``tests/cli/test_startup.py``
checks every name here against its registry, so a model added there fails that test until it
is listed here too.
"""

from __future__ import annotations

#: the keys of :data:`labkit.fit.models.MODELS`, in its order
FIT_MODELS = ("power-law", "pfr-force", "spin-critical", "cone-angle", "mbs-force", "mbs-distance")

#: :data:`labkit.fit.models.PAPER_OMEGA_C`, the fixed omega_c of Eq. 6.37 (rad/s)
PAPER_OMEGA_C = 3000.0
