"""The benchmark scripts run in their short mode and write every figure (timings are
reported, never asserted)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

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
    for key in ("bare_us", "motors_us", "stack_us", "plain_us", "plain_limp_us"):
        assert 0 < row[key]["min"] <= row[key]["median"] <= row[key]["max"]
    assert row["stack_over_bare"] > 0 and row["realtime_factor"] > 0
    assert row["stack_over_plain"] > 0
    # The peer really moves its arms, and tracks (PyBullet's motors with feed-forward).
    assert row["plain_targets"] >= row["arms"] and row["plain_tracking_error_rad"] < 1e-2
    assert figures["fleet"]["bringup_s"] > 0 and figures["fleet"]["peak_rss_mb"] > 0
    tracking = figures["tracking"]
    assert 0 < tracking["armfleet_max_error_rad"] < 1e-3
    assert tracking["position_control_max_error_rad"] > 0
    assert "c/d" in result.stdout and "c/a" in result.stdout and "tracking" in result.stdout


def test_step_phases_benchmark_times_every_phase(tmp_path: Path) -> None:
    out = tmp_path / "phases.json"
    command = [sys.executable, str(BENCHMARKS / "step_phases.py"), "--arms", "2"]
    result = subprocess.run(
        [*command, "--repeats", "1", "--steps", "50", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    phases = json.loads(out.read_text())["phases_us"]
    assert set(phases) >= {"controllers", "write", "physics", "read", "contacts"}
    assert phases["physics"] > 0 and phases["controllers"] > 0 and phases["read"] > 0
    assert "total" in result.stdout


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


def test_planner_choice_short_mode_compares_both_libraries(tmp_path: Path) -> None:
    pytest.importorskip("roboplan", reason="the comparison needs the bench extra (roboplan)")
    out = tmp_path / "planner_choice.json"
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / "planner_choice.py"), "--short", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    figures = json.loads(out.read_text())
    assert figures["settings"]["model_disagreements"].startswith("0/")  # one collision model
    assert set(figures["straight_line_collides"]) == {"1 arm", "2 arms", "all"}
    rows = {(row["planner"], row["kind"]): row for row in figures["rows"]}
    assert {"OMPL", "RoboPlan"} <= {planner for planner, _ in rows}
    for row in rows.values():
        assert row["problems"] == 3 and 0 <= row["solved"] <= 3
        if row["solved"]:
            assert 0 < row["plan_ms_median"] <= row["plan_ms_p95"]
            assert row["length_ratio_median"] >= 1 - 1e-9  # never shorter than the straight line
    assert rows[("OMPL", "2 arms")]["touching_paths"] == 0  # its margin keeps paths clear
    assert "RoboPlan/OMPL" in result.stdout


def test_planner_choice_without_roboplan_says_how_to_get_it(tmp_path: Path) -> None:
    hidden = tmp_path / "roboplan"
    hidden.mkdir()
    (hidden / "__init__.py").write_text("raise ImportError('roboplan hidden by the test')\n")
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / "planner_choice.py"), "--short"],
        capture_output=True, text=True, timeout=120, env=os.environ | {"PYTHONPATH": str(tmp_path)},
    )  # fmt: skip
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "planner_choice needs roboplan: pip install -e .[bench]"
    ]


def test_planning_benchmark_short_mode_executes_clean_plans_and_collides_straight(
    tmp_path: Path,
) -> None:
    out = tmp_path / "planning.json"
    runtime = tmp_path / "runtime"
    runtime.mkdir()
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / "planning.py"), "--short", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
        env=os.environ | {"XDG_RUNTIME_DIR": str(runtime)},
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # the straight motions' protective stops are counted, not logged
    figures = json.loads(out.read_text())
    assert set(figures["classes"]) == {"1 arm", "2 arms", "all"}
    records = figures["problems"]
    assert [r["kind"] for r in records] == ["1 arm", "2 arms", "1 arm", "2 arms"]
    assert [r["goal"] for r in records] == ["joint", "joint", "pose", "joint"]
    solved = [r for r in records if r["solved"]]
    assert solved, [r["error"] for r in records]
    for r in solved:
        # PyBullet, not the planner, says what touched: nothing, and nothing stopped.
        assert (r["contact_steps"], r["pairs"], r["stops"]) == (0, [], 0), r["index"]
        assert r["recheck_touches"] is False  # the independent model agrees
        assert "certify" in r["phases_ms"]  # the planner proved the path before returning it
        assert r["length_ratio"] >= 1 - 1e-9  # no path is shorter than its straight line
        assert r["tracking_error_rad"] < 2e-3  # the stack tracks to ~3e-5 rad (field notes)
        if r["goal"] == "pose":  # 2e-3 rad on a ~1 m arm: 2 mm at most
            assert r["pose_error_mm"] < 2.0 and r["pose_error_deg"] < 0.5
        assert r["request_cpu_ms"] > 0.0  # the process's CPU time, not a wall clock
        assert r["duration_s"] > 0.0 and r["rest_to_rest_s"] > 0.0
    for r in records:
        straight = r["straight"]
        if straight["stops"]:
            assert straight["contact_steps"] > 0  # a protective stop follows a contact
        if r["solved"] and r["goal"] == "joint" and r["straight_clear"]:
            # the planner proved the straight joint line clear: in PyBullet it is
            assert not r["straight_collided"], r["index"]
    assert figures["classes"]["all"]["straight"]["collided"] >= 1  # goals across the table
    assert "targets:" in result.stdout and "STRAIGHT move_together" in result.stdout
    # VAMP does not build here: the comparison says its figures are the published ones.
    assert "against VAMP" in result.stdout and "published" in figures["vamp"]["vamp"]["source"]
    assert figures["vamp"]["armfleet"]["cpu_ms"]["median"] > 0.0


def test_planning_threads_benchmark_short_mode_times_both_sides(tmp_path: Path) -> None:
    out = tmp_path / "planning_threads.json"
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / "planning_threads.py"), "--short", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    figures = json.loads(out.read_text())
    assert figures["moves"] == 2
    for key in ("read_ms", "start_ms", "plan_on_stepping_thread_ms"):
        assert figures[key]["max"] >= figures[key]["median"]
    assert figures["plan_on_stepping_thread_ms"]["median"] > 0
    assert "share of the plan" in result.stdout
