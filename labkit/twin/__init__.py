"""The virtual twin of a rig file: run its protocols on the model plant, fit, and compare what
comes back with what went in (docs/explanation/twin.md). Entry point: :func:`labkit.twin.run.run_twin`."""
