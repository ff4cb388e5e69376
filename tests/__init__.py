"""Test suite of particlebot: firmware logic, protocol, host package and firmware in the loop."""
