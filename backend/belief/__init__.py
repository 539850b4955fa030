"""What the console believes each vehicle is doing: the last command sent, the command it
probably runs (with its probability and the runner-up), where it probably is (with an
uncertainty) and whether a Surface is on its way.

One :class:`backend.belief.model.Belief` per vehicle, keyed by the vehicle's name (one today,
``nemesys``; a fleet next). The page renders it and decides nothing itself.

* :mod:`backend.belief.model`: the shapes (``/api/vehicle`` -> ``belief``, the ``belief``
  message of ``/ws``);
* :mod:`backend.belief.odds`: which command runs, on a one-way link (pure);
* :mod:`backend.belief.reckoning`: the position run forward without telemetry (pure);
* :mod:`backend.belief.estimate`: a belief from the evidence (records, echoes, the last fix);
* :mod:`backend.belief.tracker`: the evidence gathered from the running console, pushed on
  change.

This module imports nothing, so that :mod:`backend.messages` can import the shapes.
"""
