"""labkit.session (see ARCHITECTURE.md)."""
