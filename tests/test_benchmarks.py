"""The benchmark scripts run in their short mode and write every figure (timings are
reported, never asserted)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def test_fleet_benchmark_short_mode_writes_every_field(tmp_path: Path) -> None:
    out = tmp_path / "fleet.json"
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / "fleet.py"), "--short", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # no PyBullet banner, no warnings
    figures = json.loads(out.read_text())
    (row,) = figures["sizes"]
    assert row["arms"] == 2
    for key in ("bare_us", "motors_us", "stack_us"):
        assert 0 < row[key]["min"] <= row[key]["median"] <= row[key]["max"]
    assert row["stack_over_bare"] > 0 and row["realtime_factor"] > 0
    assert figures["fleet"]["bringup_s"] > 0 and figures["fleet"]["peak_rss_mb"] > 0
    tracking = figures["tracking"]
    assert 0 < tracking["armfleet_max_error_rad"] < 1e-3
    assert tracking["position_control_max_error_rad"] > 0
    assert "c/a" in result.stdout and "tracking" in result.stdout


def test_ik_benchmark_short_mode_reports_every_model(tmp_path: Path) -> None:
    out = tmp_path / "ik.json"
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / "ik.py"), "--short", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    figures = json.loads(out.read_text())
    from armfleet.description import ModelLibrary

    assert [row["model"] for row in figures["models"]] == ModelLibrary().names
    for row in figures["models"]:
        assert row["poses"] == 10 and row["success_rate"] >= 0.8  # 10/10 on every model so far
        assert 0 < row["median_ms"] <= row["p95_ms"] <= row["max_ms"]
        assert row["model"] in result.stdout
