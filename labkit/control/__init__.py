"""labkit.control (see ARCHITECTURE.md)."""
