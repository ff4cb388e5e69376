"""Runs of the simulated world: the run folder, the published CSV, snapshots, pictures, video."""
