"""The laser-trace pipeline: frames -> trace -> gathered points -> pattern fit -> checks."""
