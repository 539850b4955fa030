"""Every vehicle of the console: a fleet on one ME link (``NEMESYS_VEHICLES``), or the single
vehicle as a fleet of one named ``nemesys`` (no address: today's frames and views).

:mod:`~backend.fleet.state` holds each vehicle's runtime record (its link, its telemetry hub,
the path it flies); :mod:`~backend.fleet.telemetry` takes what each vehicle reports (poses,
status, acknowledgements) into its record, the mission log and the command manager;
:mod:`~backend.fleet.views` answers ``/api/vehicles``, ``/api/vehicles/{name}`` and
``/api/transmitter`` (the models: :mod:`~backend.fleet.models`).
"""
