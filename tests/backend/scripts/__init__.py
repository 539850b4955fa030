"""tests.backend.scripts package."""
