"""A world served to ROS 2 by ``armfleet spawn ... --ros`` in a subprocess, and real ROS 2
nodes (``tests/ros_client.py``, rclpy) run as subprocesses against it.

Each test file's world gets its own ROS domain: 100 plus the xdist worker's number, so
files running at once on other workers never see each other's nodes (a worker runs one
file at a time). Every process uses armfleet's loopback profile: nothing leaves the
machine.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.remote_world import WorldProcess

pytest.importorskip("rclpy", reason="ROS 2 tests need armfleet[ros]")
pytest.importorskip("control_msgs", reason="ROS 2 tests need ros_interfaces/ built")

from armfleet.ros.loopback import loopback_environment

CLIENT = Path(__file__).with_name("ros_client.py")
#: Longest a node may take (discovery, a goal) [s]: a generous bound, not a timing test.
NODE_TIMEOUT_S = 120.0
#: Domains of the test worlds: this plus the xdist worker's number.
FIRST_DOMAIN = 100


def ros_domain_id() -> int:
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    return FIRST_DOMAIN + int(worker.removeprefix("gw") or 0)


def node_env() -> dict[str, str]:
    return os.environ | loopback_environment() | {"PYTHONUNBUFFERED": "1"}


def ros_node(domain: int, command: str, arguments: dict[str, Any]) -> Any:
    """Run one ROS 2 node to its end; what it printed, parsed."""
    done = subprocess.run(
        [sys.executable, str(CLIENT), str(domain), command, json.dumps(arguments)],
        capture_output=True,
        text=True,
        timeout=NODE_TIMEOUT_S,
        env=node_env(),
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def start_ros_node(domain: int, command: str, arguments: dict[str, Any]) -> subprocess.Popen[str]:
    """Start one ROS 2 node in the background (to be killed by the test)."""
    return subprocess.Popen(
        [sys.executable, str(CLIENT), str(domain), command, json.dumps(arguments)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=node_env(),
    )


def ros_world(runtime_dir: Path, domain: int, *arms: str) -> WorldProcess:
    """bob at (0, 0) and toby at (1, 0) (or ``arms``: spawn's arguments), paced to the
    wall clock, served to ROS 2 on ``domain``."""
    spawn = list(arms) or ["bob", "toby", "--at", "0,0", "1,0"]
    world = WorldProcess(
        runtime_dir, *spawn, "--no-viewer", "--realtime", "--ros", "--ros-domain", str(domain)
    )
    assert any(line.startswith("ros: ") for line in world.stdout), world.stdout
    return world


def serve(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[WorldProcess, int]]:
    """A test file's ``served`` fixture: the world and its ROS domain, stopped after."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    domain = ros_domain_id()
    world = ros_world(tmp_path, domain)
    try:
        yield world, domain
    finally:
        assert world.stop() == 0, world.stderr[-20:]
