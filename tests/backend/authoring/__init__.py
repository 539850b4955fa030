"""tests.backend.authoring package."""
