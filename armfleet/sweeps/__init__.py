"""Sweeps: a scenario (a launch spec and a task) run for many seeds on Ray, one row per run.

See docs/sweeps.md.
"""
