"""Tests of the host package: radios, virtual swarm, console, logs and command line."""
