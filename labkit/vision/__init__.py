"""labkit.vision (see ARCHITECTURE.md)."""
