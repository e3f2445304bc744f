"""Where the data folders (descriptions, controller files, launch specs) are.

In a source checkout they sit at the top of the repository; in an installed
wheel they ship as ``armfleet/_data/<folder>``. Both layouts are found without
configuration.
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent.parent  # armfleet/
DATA_FOLDERS = ("description", "controllers", "launch_specs")


def data_dir(folder: str) -> Path:
    """Return the folder ``folder`` (one of :data:`DATA_FOLDERS`) of this armfleet.

    Raises:
        FileNotFoundError: if neither the installed nor the source layout has it.
    """
    if folder not in DATA_FOLDERS:
        raise ValueError(f"unknown data folder {folder!r}; choose from {', '.join(DATA_FOLDERS)}")
    candidates = (_PACKAGE_DIR / "_data" / folder, _PACKAGE_DIR.parent / folder)
    for candidate in candidates:
        if candidate.is_dir():
            return candidate
    searched = ", ".join(str(c) for c in candidates)
    raise FileNotFoundError(f"armfleet data folder {folder!r} not found; searched: {searched}")
