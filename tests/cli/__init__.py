"""tests.cli package."""
