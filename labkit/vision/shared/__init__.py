"""What both vision pipelines use (ADR 0034): frame sources (``frames``, ``image_size``,
``exposure``), the pattern curves of Eq. 6.38 and how a pattern is told (``curves``), the one
verdict type (``verdict``) and the typed results' base (``result``). No module here imports
``labkit.vision.laser`` or ``labkit.vision.strobe``."""
