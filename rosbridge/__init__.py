"""rosbridge package."""
