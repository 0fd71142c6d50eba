"""labkit: measure, replay and model polarity-free magnetic repulsion (PFR) rigs.

See README.md for the two commands that set up and run it, and docs/DEVELOPING.md for the layout.
"""

__version__ = "0.1.0"
