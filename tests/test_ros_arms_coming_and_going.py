"""Arms that come and go while the world is served to ROS 2 (issue 29): an arm spawned
through the live API gets its topics and controllers, and a goal it is following when it
is removed ends aborted with the reason, its result delivered; the other arms go on."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import armfleet
from tests.remote_world import WorldProcess, wait_until
from tests.ros_world import NODE_TIMEOUT_S, ros_node, serve, start_ros_node

ABORTED, SUCCEEDED = 6, 4
CARL = [f"carl_panda_joint{i}" for i in range(1, 8)]


def _trajectory(positions: np.ndarray, seconds: float) -> dict[str, object]:
    return {
        "joint_names": CARL,
        "points": [{"positions": positions.tolist(), "time_from_start": seconds}],
    }


@pytest.fixture
def served(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[WorldProcess, int]]:
    """bob and toby served to ROS 2 (tests/ros_world.py), and the domain."""
    yield from serve(tmp_path, monkeypatch)


def test_a_spawned_arm_is_served_and_its_removal_ends_its_goal(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        carl = client.spawn("carl", at=(2.0, 0.0))
        seen = ros_node(domain, "watch", {"arm": "carl", "seconds": 0.2})
        assert seen["joint_state"]["name"][:7] == CARL
        assert seen["tf_static"]["carl_base_link"]["translation"] == pytest.approx([2, 0, 0])
        start = carl.positions
        toby_start = client.arm("toby").positions
        step = np.array([0.5, -0.3, 0.3, -0.4, 0.3, 0.4, -0.5])
        trajectory = {
            "joint_names": CARL,
            "points": [{"positions": (start + step).tolist(), "time_from_start": 5.0}],
        }
        node = start_ros_node(
            domain, "goal", {"arm": "carl", "goals": [{"trajectory": trajectory}]}
        )
        try:
            assert wait_until(lambda: np.max(np.abs(carl.positions - start)) > 0.01, timeout=60)
            client.remove("carl")
            out, err = node.communicate(timeout=NODE_TIMEOUT_S)
        finally:
            if node.poll() is None:
                node.kill()
        assert node.returncode == 0, err[-2000:]
        [result] = json.loads(out.strip().splitlines()[-1])
        assert result["status"] == ABORTED, result
        assert "carl was removed" in result["error_string"]
        assert sorted(client.info().arms) == ["bob", "toby"]
        np.testing.assert_allclose(client.arm("toby").positions, toby_start, atol=1e-4)
        # Spawned again under the same name, carl is served again.
        client.spawn("carl", at=(2.0, 0.0))
        back = client.arm("carl").positions
        goal = {"trajectory": _trajectory(back + 0.5 * step, 1.5)}
        [again] = ros_node(domain, "goal", {"arm": "carl", "goals": [goal]})
        assert again["status"] == SUCCEEDED, again
