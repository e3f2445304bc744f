"""A failing tracking test leaves its recording and tracking plots next to the test report."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

from PIL import Image

ROOT = Path(__file__).resolve().parents[1]

CONFTEST = (
    "from tests.conftest import KEPT_RECORDINGS, keep_on_failure, pytest_runtest_makereport\n"
)
TESTS = textwrap.dedent(
    """
    import armfleet

    def record_a_move(path):
        with armfleet.World() as world, armfleet.record(world, path):
            bob = world.spawn("bob")
            bob.move_to(bob.positions + 0.2)
            world.run(0.4)

    def test_tracking_that_fails(tmp_path, keep_on_failure):
        mcap = tmp_path / "run.mcap"
        keep_on_failure(mcap)
        record_a_move(mcap)
        assert False, "max tracking error 1.2e-3 rad > 1e-3 rad (made to fail)"

    def test_tracking_that_passes(tmp_path, keep_on_failure):
        mcap = tmp_path / "run.mcap"
        keep_on_failure(mcap)
        record_a_move(mcap)
    """
)


def test_a_failing_test_leaves_its_recording_and_plot_beside_the_report(tmp_path: Path) -> None:
    (tmp_path / "conftest.py").write_text(CONFTEST)
    (tmp_path / "test_inner.py").write_text(TESTS)
    report = tmp_path / "reports" / "junit.xml"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--junitxml={report}"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1, result.stdout + result.stderr  # one failure, one pass
    artifacts = tmp_path / "reports" / "test-artifacts"
    folders = [p.name for p in artifacts.iterdir()]
    assert folders == ["test_inner.py_test_tracking_that_fails"], folders
    folder = artifacts / folders[0]
    assert (folder / "run.mcap").stat().st_size > 10_000
    with Image.open(folder / "run_bob.png") as image:
        assert image.size == (1200, 1220)
    assert "failure artifacts" in result.stdout and str(folder / "run_bob.png") in result.stdout
