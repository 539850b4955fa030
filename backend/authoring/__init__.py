"""backend.authoring package."""
