"""labkit.sim (see ARCHITECTURE.md)."""
