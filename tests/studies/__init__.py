"""Tests of the simulation studies: definitions, measures, reports and the Dask engine."""
