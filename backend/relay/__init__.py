"""Commands from a console without the transmitter (issue 24, item 4): the shore's relay
link and sender (``NEMESYS_TARGET=relay``), the outbox worker of the console that holds the
transmitter, on the PostgreSQL log they share."""
