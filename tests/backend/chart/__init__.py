"""tests.backend.chart package."""
