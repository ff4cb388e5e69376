"""Tests of the video tracker, the statistics of Table S2 and the pictures of runs."""
