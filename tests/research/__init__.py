"""Tests of the research scripts that draw the docs figures from the kept study data."""
