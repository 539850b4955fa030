"""backend.commands.manager package."""
