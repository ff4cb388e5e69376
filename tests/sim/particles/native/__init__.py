"""Tests of the native firmware logic (through the C API) as particles of the world."""
