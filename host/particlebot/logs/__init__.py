"""Session logs: JSON lines written as things happen, read back, exported to CSV or replayed."""
