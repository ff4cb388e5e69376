"""Tests of the radio protocol: generator, frame codec, stream decoder and golden vectors."""
