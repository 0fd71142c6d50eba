"""labkit.protocols (see ARCHITECTURE.md)."""
