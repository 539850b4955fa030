"""backend.chart package."""
