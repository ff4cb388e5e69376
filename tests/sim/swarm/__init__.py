"""Tests of the one clock that steps the world, the particles and the air."""
