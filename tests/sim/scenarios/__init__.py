"""Tests of scenarios: placements, scenario files (ours and the published ones), worlds."""
