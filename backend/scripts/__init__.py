"""backend.scripts.operations package."""
