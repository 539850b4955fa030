"""backend.mission_log package."""
