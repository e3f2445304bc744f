"""The world speaks ROS 2's real message types (issue 29): a node looking at the graph,
as ``ros2 topic info --verbose`` does, sees the type names and type hashes (RIHS01) a ROS
2 installation has, including tf2_msgs, which armfleet builds from its released
interface files (ros_interfaces/)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.remote_world import ARMFLEET, runtime_env
from tests.ros_world import ros_domain_id, ros_node, ros_world

#: tf2_msgs/msg/TFMessage's hash as a ROS 2 Jazzy installation reports it (``ros2 topic
#: info /tf --verbose`` on a robot's /tf, published in a public issue); the type has not
#: changed since, so every distribution since Iron reports the same.
TF_MESSAGE_HASH = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"


def test_the_graph_shows_ros_2s_own_types_and_hashes(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    domain = ros_domain_id()
    world = ros_world(tmp_path, domain, "bob", "--at", "0,0")
    try:
        topics = ["/tf", "/tf_static", "/clock", "/bob/joint_states"]
        seen = ros_node(domain, "graph", {"arm": "bob", "topics": topics})
    finally:
        assert world.stop() == 0
    [tf] = seen["/tf"]
    assert tf["node"] == "armfleet"
    assert tf["type"] == "tf2_msgs/msg/TFMessage"
    assert tf["hash"] == TF_MESSAGE_HASH
    assert seen["/tf_static"][0]["hash"] == TF_MESSAGE_HASH
    assert seen["/clock"][0]["type"] == "rosgraph_msgs/msg/Clock"
    # The index's sensor_msgs, as the node's own JointState class hashes it.
    from sensor_msgs.msg import JointState

    [state] = seen["/bob/joint_states"]
    assert state["type"] == "sensor_msgs/msg/JointState"
    assert state["hash"] == _hash_of(JointState)


def _hash_of(message_type: type) -> str:
    """The type hash rosidl generated for ``message_type`` (its JSON description)."""
    module = sys.modules[message_type.__module__]
    package = module.__name__.split(".")[0]
    share = Path(sys.prefix) / "share" / package / "msg" / f"{message_type.__name__}.json"
    described = json.loads(share.read_text())
    return str(described["type_hashes"][0]["hash_string"])


def test_ros_without_its_interfaces_is_one_line_and_exit_2(tmp_path: Path) -> None:
    """With rclpy but without tf2_msgs built, --ros says how to build it, before any arm
    comes up. (An import hook in the child hides tf2_msgs, as if never built.)"""
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text(
        "import sys\n"
        "class Hide:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'tf2_msgs':\n"
        "            raise ModuleNotFoundError(name)\n"
        "sys.meta_path.insert(0, Hide())\n"
    )
    env = runtime_env(tmp_path) | {"PYTHONPATH": os.pathsep.join([str(hide), os.getcwd()])}
    done = subprocess.run(
        [*ARMFLEET, "spawn", "bob", "--at", "0,0", "--no-viewer", "--ros", "--duration", "1"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert done.returncode == 2, done.stderr
    [line] = done.stderr.strip().splitlines()
    assert (
        "tf2_msgs" in line and "pip install --no-build-isolation ./ros_interfaces/tf2_msgs" in line
    )
    assert "Traceback" not in done.stderr and "spawned" not in done.stdout
