"""docs/ros2.md as a newcomer follows it (issue 29): its install commands are the ones the
test install runs, its world command starts the seeds' two arms on ROS 2, and its Python
node, run as written as a script (on this test's ROS domain), drives bob through the
action and toby through the topic, both of which then stand where the node sent them."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

import armfleet
from tests.ros_world import NODE_TIMEOUT_S, node_env, ros_domain_id, ros_world

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "ros2.md"
DOCUMENTED_DOMAIN = 7


def _blocks(language: str) -> list[str]:
    return re.findall(rf"^ *```{language}\n(.*?)^ *```", PAGE.read_text(), re.DOTALL | re.MULTILINE)


def _dedent(block: str) -> str:
    lines = block.splitlines()
    indent = min(len(line) - len(line.lstrip()) for line in lines if line.strip())
    return "\n".join(line[indent:] for line in lines) + "\n"


def test_the_install_commands_are_the_test_installs() -> None:
    install = _dedent(_blocks("bash")[0])
    script = (ROOT / "scripts" / "test.sh").read_text()
    assert 'pip install -e ".[ros]"' in install
    built = re.search(
        r"--no-build-isolation (\./ros_interfaces/\S+ \./ros_interfaces/\S+)", install
    )
    assert built is not None
    assert built.group(1) in script.replace("\\\n  ", "")


def test_the_world_command_and_the_node_work_as_written(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    [spawn] = [b for b in map(_dedent, _blocks("bash")) if "armfleet spawn" in b]
    arguments = spawn.split("armfleet spawn", 1)[1].split()
    domain = ros_domain_id()
    at = arguments.index("--ros-domain")
    assert arguments[at + 1] == str(DOCUMENTED_DOMAIN)
    arguments[at : at + 2] = []  # ros_world adds this test's own domain, and --no-viewer
    arguments.remove("--ros")
    world = ros_world(tmp_path, domain, *arguments)
    try:
        with armfleet.connect(world.address) as client:
            bob_start, toby_start = client.arm("bob").positions, client.arm("toby").positions
            [node] = _blocks("python")
            script = tmp_path / "my_node.py"
            script.write_text(
                _dedent(node).replace(f"domain_id={DOCUMENTED_DOMAIN}", f"domain_id={domain}")
            )
            done = subprocess.run(
                [sys.executable, str(script)],
                capture_output=True,
                text=True,
                timeout=NODE_TIMEOUT_S,
                env=node_env() | {"PYTHONPATH": os.getcwd()},
            )
            assert done.returncode == 0, done.stderr[-3000:]
            lines = done.stdout.splitlines()
            assert lines[0].startswith("bob is at")
            assert "bob's goal: 4 0" in lines
            expected_bob = bob_start + np.array([0.5, 0.3, 0, 0, 0, 0, 0])
            np.testing.assert_allclose(client.arm("bob").positions, expected_bob, atol=0.01)
            expected_toby = toby_start + np.array([-0.5, 0, 0, 0, 0, 0, 0])
            np.testing.assert_allclose(client.arm("toby").positions, expected_toby, atol=0.01)
    finally:
        assert world.stop() == 0
