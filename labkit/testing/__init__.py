"""Helpers for testing code that uses labkit, and for labkit's own tests."""
