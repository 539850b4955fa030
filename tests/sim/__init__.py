"""tests.sim package."""
