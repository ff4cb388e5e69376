"""Tests of particlebot.commands."""
