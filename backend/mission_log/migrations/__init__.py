"""The mission log's migrations (Alembic revisions), oldest first:
:mod:`backend.mission_log.migrating` says how they run and how to add one."""
