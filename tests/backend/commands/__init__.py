"""tests.backend.commands package."""
