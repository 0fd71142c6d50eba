"""labkit.emulators (see ARCHITECTURE.md)."""
