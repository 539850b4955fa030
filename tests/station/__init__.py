"""tests.station package."""
