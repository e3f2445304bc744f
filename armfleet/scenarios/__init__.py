"""Scenarios: tasks run on a world for one seed (reach, handover, crossing).

A sweep (:mod:`armfleet.sweeps`) runs them for many seeds; the learning environments
(:mod:`armfleet.envs`) reuse their scenes and targets. ``task:`` entries of the shipped
specs name them (``armfleet.scenarios.handover:handover``).

Rule: imports :mod:`armfleet.world` and the core below it; never Ray, a sweep or an
environment.
"""
