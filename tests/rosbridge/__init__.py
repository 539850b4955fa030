"""tests.rosbridge package."""
