"""Reports: a self-contained folder (markdown + PNG figures) for a session or result file."""
