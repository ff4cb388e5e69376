"""Tests of particlebot.fleet."""
