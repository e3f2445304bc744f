"""Runtime: what every room of a world runs on, and nothing about arms.

Owns the message bus (:mod:`~armfleet.runtime.bus`), handle lifetimes
(:mod:`~armfleet.runtime.lifetime`), the step guard that lets one thread at a time step
or change a world (:mod:`~armfleet.runtime.step_guard`) and the queue other threads hand
work over with (:mod:`~armfleet.runtime.request_queue`).

Rule: imports only :mod:`armfleet.checks`, :mod:`armfleet.errors` and
:mod:`armfleet.messages`.
"""
