"""Tests of particlebot.logs."""
