"""Scenarios: everything one run of the world needs (swarm and placement, lamp, obstacles,
objects, failures, controller, physics, outputs), read from our TOML files or the published
simulator's configuration files, and built into a world."""
