"""Particles of the simulated world at every fidelity: models, native logic, emulated image."""
