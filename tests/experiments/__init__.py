"""Tests of particlebot.experiments."""
