"""Tests of the firmware logic, run through the native library (particlebot.firmware.native)."""
