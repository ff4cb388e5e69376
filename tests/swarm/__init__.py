"""Tests of particlebot.swarm."""
