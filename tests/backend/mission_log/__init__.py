"""tests.backend.mission_log package."""
