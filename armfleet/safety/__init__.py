"""Safety: protective stops when an arm touches what it must not.

Owns :class:`~armfleet.safety.safety_supervisor.SafetySupervisor`, which stops any
:class:`~armfleet.safety.safety_supervisor.Stoppable` arm (see docs/safety.md).

Rule: imports :mod:`armfleet.controllers`, :mod:`armfleet.physics` and below; never an
arm handle or the world.
"""
