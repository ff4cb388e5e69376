"""Tests of the one 802.15.4 medium every simulated radio shares."""
