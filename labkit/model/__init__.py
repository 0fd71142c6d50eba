"""labkit.model (see ARCHITECTURE.md)."""
