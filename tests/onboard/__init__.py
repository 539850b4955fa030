"""tests.onboard package."""
