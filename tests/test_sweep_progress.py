"""The sweep's progress bar counts this call's runs and failures; a resumed sweep says in
its label how many runs the file already held (no unexplained counter)."""

from __future__ import annotations

import pytest

from armfleet.sweeps.progress import SweepProgress


def _bar_text(capsys: pytest.CaptureFixture[str], done_before: int) -> str:
    progress = SweepProgress(5, done_before, enabled=True)
    progress.update(2, 1)
    progress.update(3, 0)
    progress.close()
    return capsys.readouterr().err


def test_a_fresh_sweep_shows_runs_and_failures_only(capsys: pytest.CaptureFixture[str]) -> None:
    text = _bar_text(capsys, 0)
    assert "5/5" in text and "failed=1" in text
    assert "kept" not in text and "already in the file" not in text


def test_a_resumed_sweep_names_the_runs_it_had(capsys: pytest.CaptureFixture[str]) -> None:
    text = _bar_text(capsys, 40)
    assert "sweep (resumed, 40 runs already in the file)" in text
    assert "5/5" in text and "kept" not in text
