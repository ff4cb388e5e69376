"""Tests of the real firmware image in simavr as particles of the world."""
