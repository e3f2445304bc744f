"""What a failing test leaves behind for a person: its recordings and their tracking plots.

A test registers an MCAP recording with the ``keep_on_failure`` fixture; if
the test then fails, :func:`save_artifacts` copies the recording to
``test-artifacts/<test id>/`` (next to the ``--junitxml`` report when there
is one, else at the repository root) and draws its tracking plots beside it.
"""

from __future__ import annotations

import re
import shutil
from collections.abc import Sequence
from pathlib import Path

import pytest

from armfleet.recording import open_recording, plot_recording

ARTIFACTS = "test-artifacts"


def artifacts_root(config: pytest.Config) -> Path:
    """``test-artifacts/`` beside the junit report if one is written, else in the rootdir."""
    xml = getattr(config.option, "xmlpath", None)
    base = Path(xml).resolve().parent if xml else config.rootpath
    return base / ARTIFACTS


def folder_for(root: Path, nodeid: str) -> Path:
    """A folder name for a test id, e.g. ``tests_test_tracking.py_test_x_panda``."""
    return root / re.sub(r"[^A-Za-z0-9_.-]+", "_", nodeid).strip("_")


def save_artifacts(recordings: Sequence[Path], folder: Path) -> list[Path]:
    """Copy each recording into ``folder`` and plot it there; returns the files written.

    A recording that cannot be plotted is still copied; the reason goes in a text file.
    """
    folder.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    for recording in recordings:
        copy = folder / recording.name
        shutil.copyfile(recording, copy)
        written.append(copy)
        try:
            written += plot_recording(open_recording(copy), output=folder).values()
        except Exception as exc:  # the test's own failure is what matters; say why, go on
            note = folder / f"{recording.stem}_plot_error.txt"
            note.write_text(f"{type(exc).__name__}: {exc}\n")
            written.append(note)
    return written
