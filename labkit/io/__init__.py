"""labkit.io (see ARCHITECTURE.md)."""
