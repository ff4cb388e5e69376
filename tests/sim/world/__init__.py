"""Tests of the 2-D physical world: contacts, magnets, friction, servo, light, obstacles."""
