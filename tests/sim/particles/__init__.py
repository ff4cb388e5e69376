"""Tests of the simulated world's particles: the vectorised controllers against the firmware."""
