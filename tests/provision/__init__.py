"""Tests of particlebot.provision."""
