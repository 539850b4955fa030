"""backend.viewer.viewer package."""
