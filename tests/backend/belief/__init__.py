"""tests.backend.belief package."""
