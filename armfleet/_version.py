"""armfleet's version, read by the build (pyproject.toml) and by every layer that reports it."""

__version__ = "0.1.0"
