"""Tests of particlebot.console."""
