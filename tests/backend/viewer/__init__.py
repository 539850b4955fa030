"""tests.backend.viewer package."""
