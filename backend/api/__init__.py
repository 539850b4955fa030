"""The console's routers (REST under /api, the live websocket at /ws)."""
