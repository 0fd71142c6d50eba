"""labkit.devices (see ARCHITECTURE.md)."""
