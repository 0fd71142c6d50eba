"""The stress cases, grouped by what they stress; the runner is :mod:`labkit.numerics.stress`."""
