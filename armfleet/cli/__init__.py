"""The ``armfleet`` command line.

Rule: the top room; may import every other. A command loads an optional room (sweeps,
Foxglove) only when it runs, so the core commands start without the extras.
"""
