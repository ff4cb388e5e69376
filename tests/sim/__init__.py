"""Tests of the real firmware image in simavr: harness, emulated swarm and console end to end."""
