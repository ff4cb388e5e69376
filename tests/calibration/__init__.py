"""Tests of the calibrations: photocell fits, Fig. S5, servo tables, and the commands."""
