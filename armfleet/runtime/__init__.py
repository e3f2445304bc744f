"""Runtime: what every room of a world runs on, and nothing about arms.

Owns the message bus (:mod:`~armfleet.runtime.bus`), handle lifetimes
(:mod:`~armfleet.runtime.lifetime`), the step guard that lets one thread at a time step
or change a world (:mod:`~armfleet.runtime.step_guard`), the queue other threads hand
work over with (:mod:`~armfleet.runtime.request_queue`) and the threads that do work which
must not hold the stepping thread (:mod:`~armfleet.runtime.worker_threads`).

Rule: imports only :mod:`armfleet.checks`, :mod:`armfleet.errors` and
:mod:`armfleet.messages`.
"""
