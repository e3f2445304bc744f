"""The ``armfleet`` command line."""
