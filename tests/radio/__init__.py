"""Tests of particlebot.radio."""
