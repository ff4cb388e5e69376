"""Tests of the run driver: run folders, the published CSV, snapshots and resume, pictures."""
