"""Several consoles on one mission log: who is in control of each vehicle (the desk, the send
gate) and what every console sees of the others' writes (live sync over PostgreSQL)."""
