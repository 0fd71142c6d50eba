"""labkit.stream (see ARCHITECTURE.md)."""
