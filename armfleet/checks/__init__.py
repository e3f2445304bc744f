"""The rules for what a user may give armfleet, one module per kind of value.

Every entry point (the Python API, the command line, the live API and launch
specs) checks what it takes with these, so all refuse the same things in the
same words: :mod:`~armfleet.checks.real_numbers` (a number is a real, finite
number, not text, bool or None), :mod:`~armfleet.checks.flags` (a flag is
True or False), :mod:`~armfleet.checks.number_ranges` (timeouts, durations,
steps, ports, coordinates, angles), :mod:`~armfleet.checks.time_step` (the
physics step) and :mod:`~armfleet.checks.user_paths` (paths and files).

Rule: the lowest room; imports only :mod:`armfleet.errors` and :mod:`armfleet.messages`.
"""
