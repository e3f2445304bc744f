"""What the environments' actions do in the physics and what their tasks reward, checked
against PyBullet's joint states and an independent Pinocchio model of each arm."""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

from typing import Any

import numpy as np
import pinocchio as pin
import pybullet as p
import pytest

from armfleet.envs import HandoverEnv, MultiArmEnv, ReachEnv
from armfleet.envs.poses import rotation_from_rpy
from armfleet.envs.tasks.handover_task import HandoverTask
from armfleet.envs.tasks.reach_task import ReachTask
from armfleet.scenarios.handover import (
    HANDOVER_AT_M,
    MAT_TO_BAR_CENTRE_M,
    frame,
    grasp,
    lifted,
)

#: An arm at rest holds its target this closely [rad] (docs: hold tolerance).
HOLD_RAD = 1e-3
#: A Cartesian target is reached this closely once the arm is at rest [m], [rad].
POSITION_M, ROTATION_RAD = 1e-3, 1e-3


def measured_joints(arm: armfleet.Arm) -> np.ndarray:
    """The arm's joint positions as PyBullet reports them [rad]."""
    body = arm.body
    indices = [body.joint_indices[i] for i in arm.kinematics.arm_indices]
    states = p.getJointStates(body.body_id, indices, physicsClientId=body._client)
    return np.array([state[0] for state in states])


def tool0_by_pinocchio(arm: armfleet.Arm) -> np.ndarray:
    """tool0's world pose from the arm's URDF and PyBullet's joint states, computed by a
    Pinocchio model of its own (not the world's TF)."""
    model = pin.buildModelFromXML(arm.description.urdf)
    data = model.createData()
    q = pin.neutral(model)
    for name, value in zip(arm.joint_names, measured_joints(arm), strict=True):
        q[model.joints[model.getJointId(name)].idx_q] = value
    pin.framesForwardKinematics(model, data, q)
    return np.array(data.oMf[model.getFrameId(arm.description.tool0)].homogeneous)


def still(env: MultiArmEnv, steps: int) -> dict[str, object]:
    """``steps`` environment steps of zero change (deltas 0, joint targets kept, grippers
    as they are); returns the last info."""
    info: dict[str, object] = {}
    for _ in range(steps):
        action = {}
        for name in env.arm_names:
            space = env.arm_action_space(name)
            entry = env.action_kind.value
            value = (
                env.commander(name).target.astype(np.float32)
                if entry == "joint_positions"
                else np.zeros(
                    6 if entry == "tool_delta" else len(env.world.arm(name).joint_names), np.float32
                )
            )
            action[name] = {entry: value}
            if "gripper" in space.spaces:
                action[name]["gripper"] = np.zeros(1, np.float32)
        info = env.step(action)[4]
    return info


def test_a_joint_position_action_brings_the_joints_there() -> None:
    env = ReachEnv(arm_count=1, action_kind="joint_positions", control_period=50)
    env.reset(seed=0)
    arm = env.world.arm("arm0")
    target = (arm.positions + np.array([0.4, -0.3, 0.3, -0.4, 0.3, 0.4, -0.5])).astype(np.float32)
    assert np.abs(measured_joints(arm) - target).max() > 0.3
    action = {"arm0": {"joint_positions": target}}
    for _ in range(40):  # 2 s
        env.step(action)
    assert np.abs(measured_joints(arm) - target).max() < HOLD_RAD
    env.close()


def test_joint_deltas_add_up_on_the_previous_target() -> None:
    env = ReachEnv(arm_count=1, action_kind="joint_deltas", control_period=20)
    env.reset(seed=0)
    arm = env.world.arm("arm0")
    start = measured_joints(arm)
    delta = np.array([0.05, -0.03, 0.04, 0.05, -0.05, 0.02, 0.05], np.float32)
    for _ in range(10):
        env.step({"arm0": {"joint_deltas": delta}})
    still(env, 60)
    np.testing.assert_allclose(
        measured_joints(arm), start + 10 * delta.astype(float), atol=HOLD_RAD
    )
    env.close()


def test_a_tool_delta_moves_tool0_by_it_along_the_world_axes() -> None:
    # toby faces bob (turned 180 degrees): a delta in its base frame would go the other way.
    env = HandoverEnv(control_period=100)
    env.reset(seed=0)
    arms = {name: env.world.arm(name) for name in ("bob", "toby")}
    before = {name: tool0_by_pinocchio(arm) for name, arm in arms.items()}
    delta = np.array([0.02, -0.015, 0.02, 0.08, -0.06, 0.1], np.float32)
    action = {name: {"tool_delta": delta, "gripper": np.zeros(1, np.float32)} for name in arms}
    info = env.step(action)[4]
    assert info["refused"] == {} and info["stopped"] == []
    still(env, 15)  # 1.5 s at rest
    for name, arm in arms.items():
        after = tool0_by_pinocchio(arm)
        moved = after[:3, 3] - before[name][:3, 3]
        assert np.linalg.norm(moved - delta[:3]) < POSITION_M, name
        wanted = rotation_from_rpy(delta[3:].astype(float)) @ before[name][:3, :3]
        assert np.linalg.norm(pin.log3(wanted.T @ after[:3, :3])) < ROTATION_RAD, name
    env.close()


def test_an_unreachable_tool_target_is_not_sent_and_the_episode_goes_on() -> None:
    env = ReachEnv(arm_count=1, action_kind="tool_delta", control_period=20)
    env.reset(seed=0)
    up = {"arm0": {"tool_delta": np.array([0, 0, 0.02, 0, 0, 0], np.float32)}}
    refusals = []
    for _ in range(80):  # 1.6 m up: well out of a Panda's reach
        _, _, terminated, _, info = env.step(up)
        assert not terminated
        refusals.append(info["refused"].get("arm0", ""))
    assert refusals[-1].startswith("arm0: tool0 cannot reach the pose"), refusals[-1]
    kept = env.commander("arm0").tool_target
    still(env, 50)
    # The arm went as high as it could and stays at the last target that was reachable.
    assert np.linalg.norm(tool0_by_pinocchio(env.world.arm("arm0"))[:3, 3] - kept[:3, 3]) < 1e-3
    env.close()


def test_reach_rewards_minus_the_distances_and_succeeds_at_the_targets() -> None:
    env = ReachEnv(arm_count=2, action_kind="joint_positions", control_period=50)
    env.reset(seed=3)
    task = env.task
    assert isinstance(task, ReachTask)
    targets = task.targets
    arms = {name: env.world.arm(name) for name in targets}
    # Joint targets that put each tool0 on its target, from the arm's own IK.
    action = {
        name: {
            "joint_positions": arm.solve_ik(targets[name]).astype(np.float32),
        }
        for name, arm in arms.items()
    }
    rewards: list[float] = []
    terminated, info = False, dict[str, Any]()
    for _ in range(80):
        _, reward, terminated, _, info = env.step(action)
        distances = [
            float(np.linalg.norm(tool0_by_pinocchio(arm)[:3, 3] - targets[name][:3, 3]))
            for name, arm in arms.items()
        ]
        bonus = task.success_bonus if info["success"] else 0.0
        assert abs(float(reward) + sum(distances) - bonus) < 1e-6
        rewards.append(float(reward))
        if terminated:
            break
    assert terminated and info["success"]
    assert -(rewards[-1] - task.success_bonus) <= 2 * task.tolerance_m
    assert rewards[0] < rewards[-1]
    env.close()


def bar_at(env: MultiArmEnv, xyz: np.ndarray) -> float:
    """Teleport the bar to ``xyz`` [m], step once (1 ms), return the reward."""
    env.world.object("bar").set_pose(tuple(xyz))
    return float(env.step(zero_tool_action(env))[1])


def zero_tool_action(env: MultiArmEnv) -> dict[str, dict[str, np.ndarray]]:
    return {
        name: {"tool_delta": np.zeros(6, np.float32), "gripper": np.zeros(1, np.float32)}
        for name in env.arm_names
    }


def test_the_dense_handover_cost_falls_as_the_bar_nears_the_mat() -> None:
    env = HandoverEnv(reward="dense", control_period=1)
    env.reset(seed=0)
    goal = HandoverTask.goal(env.world)
    far = env.world.object("bar").position + np.array([0.0, 0.0, 0.12])  # over the pick table
    # Straight at the goal, from above bob's table to 4 cm from the mat, under the hands.
    fractions = np.linspace(0.0, 0.95, 8)
    rewards = [bar_at(env, goal + (1 - s) * (far - goal)) for s in fractions]
    # Nearer by d raises the reward by at least d / 2 (the docstring's bound), less the
    # bar's fall in the 1 ms step (5 um).
    nearer = np.diff(fractions) * np.linalg.norm(far - goal)
    assert np.all(np.diff(rewards) > 0.5 * nearer - 1e-4), rewards
    env.close()


def test_the_sparse_handover_reward_is_given_only_for_the_bar_resting_on_the_mat() -> None:
    env = HandoverEnv(reward="sparse", control_period=200)
    env.reset(seed=0)
    goal = HandoverTask.goal(env.world)
    rewards = [float(env.step(zero_tool_action(env))[1]) for _ in range(3)]
    assert rewards == [0.0, 0.0, 0.0]  # the bar on its table
    # On the mat but 3 cm along it from the goal (2 cm tolerance): no reward.
    env.world.object("bar").set_pose(tuple(goal + np.array([0.03, 0.0, 0.001])))
    _, reward, terminated, _, info = env.step(zero_tool_action(env))
    assert (reward, terminated, info["success"]) == (0.0, False, False)
    assert 0.025 < info["bar_to_goal_m"] < 0.035
    # Falling onto the goal from 5 cm: nothing until it rests, then 1 and the end.
    env.world.object("bar").set_pose(tuple(goal + np.array([0.0, 0.0, 0.05])))
    env.world.step()  # 1 ms (an environment step is 200)
    assert np.linalg.norm(env.world.object("bar").velocity) > 0  # falling
    _, reward, terminated, _, info = env.step(zero_tool_action(env))
    assert (reward, terminated, info["success"]) == (1.0, True, True)
    assert info["bar_to_goal_m"] < 0.002
    env.close()


@pytest.mark.parametrize("on_stop", ["terminate", "reset"])
def test_a_protective_stop_ends_the_episode_or_is_lifted(on_stop: str) -> None:
    env = ReachEnv(arm_count=1, action_kind="joint_positions", control_period=50, on_stop=on_stop)
    env.reset(seed=0)
    arm = env.world.arm("arm0")
    down = arm.positions
    down[1], down[3] = 1.7, -0.1  # leaning far forward: the fingers meet the floor
    action = {"arm0": {"joint_positions": down.astype(np.float32)}}
    for _ in range(60):
        _, _, terminated, _, info = env.step(action)
        if info["stopped"]:
            break
    assert info["stopped"] == ["arm0"] and env.world.safety.stops == 1
    assert terminated is (on_stop == "terminate")
    if on_stop == "reset":
        assert arm.mode is not armfleet.ArmMode.PROTECTIVE_STOP
        np.testing.assert_allclose(env.commander("arm0").target, arm.positions)  # rebased
        home = np.array(arm.description.home[: len(arm.joint_names)], np.float32)
        back = {"arm0": {"joint_positions": home}}
        for _ in range(40):
            _, _, terminated, _, info = env.step(back)
        assert not terminated and info["stopped"] == []
        assert np.abs(measured_joints(arm) - home).max() < HOLD_RAD
    env.close()


def test_the_gripper_entry_closes_and_opens_the_fingers() -> None:
    env = HandoverEnv(control_period=100)
    env.reset(seed=0)
    bob = env.world.arm("bob")
    action = zero_tool_action(env)
    action["bob"]["gripper"] = np.ones(1, np.float32)
    for _ in range(8):
        env.step(action)
    assert bob.gripper.width < 0.005 and bob.gripper.mode is armfleet.GripperMode.CLOSED
    observation = env.step(zero_tool_action(env))[0]
    still(env, 8)
    assert abs(bob.gripper.width - bob.gripper.max_width) < 1e-3
    assert observation["bob"]["gripper_width"][0] < bob.gripper.max_width
    env.close()


def pose_matrix(vector: np.ndarray) -> np.ndarray:
    """4x4 pose of an observed (x, y, z, qx, qy, qz, qw)."""
    pose = np.eye(4)
    pose[:3, :3] = pin.Quaternion(np.asarray(vector[3:], dtype=float)).normalized().matrix()
    pose[:3, 3] = vector[:3]
    return pose


class ScriptedHandover:
    """A policy of straight tool moves (deltas of at most the action bounds) and gripper
    commands, seeing the world only through the environment's observations."""

    def __init__(self, env: MultiArmEnv) -> None:
        self.env = env
        self.closed = {"bob": False, "toby": False}
        world = env.world  # a constant of each arm: where its tcp sits on tool0
        self.tcp_in_tool0 = {
            arm: np.linalg.solve(
                world.tf.world_pose(f"{arm}_tool0"), world.tf.world_pose(f"{arm}_tcp")
            )
            for arm in self.closed
        }
        self.rewards: list[float] = []
        self.observation, _ = env.reset(seed=3)
        self.terminated = False

    def step(self, deltas: dict[str, np.ndarray]) -> None:
        action = {
            arm: {
                "tool_delta": deltas.get(arm, np.zeros(6)).astype(np.float32),
                "gripper": np.array([float(closed)], np.float32),
            }
            for arm, closed in self.closed.items()
        }
        self.observation, reward, self.terminated, _, info = self.env.step(action)
        assert info["refused"] == {} and info["stopped"] == [], info
        self.rewards.append(float(reward))

    def seen(self, name: str) -> np.ndarray:
        """An object's pose as bob observes it."""
        return pose_matrix(self.observation["bob"]["objects"][name])

    def tcp(self, arm: str) -> np.ndarray:
        return pose_matrix(self.observation[arm]["tool_pose"]) @ self.tcp_in_tool0[arm]

    def wait(self, steps: int = 200) -> None:
        """Until every joint is still (or ``steps``)."""
        for _ in range(steps):
            self.step({})
            speeds = [np.abs(o["joint_velocities"]).max() for o in self.observation.values()]
            if max(speeds) < 1e-3 or self.terminated:
                return

    def move(self, arm: str, tcp: np.ndarray) -> None:
        """tcp to ``tcp`` in a straight line, at the largest steps the actions take."""
        goal = tcp @ np.linalg.inv(self.tcp_in_tool0[arm])
        limits = np.array([0.02] * 3 + [0.1] * 3)
        for _ in range(300):
            target = self.env.commander(arm).tool_target  # where the deltas have sent it
            error = np.concatenate(
                [goal[:3, 3] - target[:3, 3], pin.rpy.matrixToRpy(goal[:3, :3] @ target[:3, :3].T)]
            )
            if np.abs(error).max() < 1e-9:
                break
            self.step({arm: np.clip(error, -limits, limits)})
        self.wait()

    def grip(self, arm: str, close: bool) -> None:
        self.closed[arm] = close
        for _ in range(25):  # 0.5 s
            self.step({})


def test_a_scripted_policy_hands_the_bar_over_through_the_action_interface() -> None:
    # The task can be done with its actions and observations alone: bob picks the bar,
    # holds it out, toby takes it and puts it on the mat (the steps of examples/handover.py,
    # as straight tool moves instead of planned ones). Sparse reward: 0 until the end.
    env = HandoverEnv(reward="sparse", control_period=20)
    policy = ScriptedHandover(env)
    pick = grasp(policy.seen("bar"), -1)
    policy.move("bob", lifted(pick))
    policy.move("bob", pick)
    policy.grip("bob", close=True)
    policy.move("bob", lifted(pick))
    bob_in_bar = np.linalg.solve(policy.seen("bar"), policy.tcp("bob"))
    policy.move("bob", frame(HANDOVER_AT_M) @ bob_in_bar)
    take = grasp(policy.seen("bar"), +1)
    policy.move("toby", lifted(take))
    policy.move("toby", take)
    policy.grip("toby", close=True)
    policy.grip("bob", close=False)
    policy.move("bob", policy.tcp("bob") @ lifted(np.eye(4), -0.15))  # back along its z
    toby_in_bar = np.linalg.solve(policy.seen("bar"), policy.tcp("toby"))
    place = lifted(policy.seen("mat"), MAT_TO_BAR_CENTRE_M + 0.002) @ toby_in_bar
    policy.move("toby", lifted(place))
    policy.move("toby", place)
    assert not policy.terminated and set(policy.rewards) == {0.0}  # held: no success yet
    policy.closed["toby"] = False
    policy.wait(50)
    assert policy.terminated and policy.rewards[-1] == 1.0
    assert set(policy.rewards[:-1]) == {0.0}
    task = env.task
    assert isinstance(task, HandoverTask)
    assert np.linalg.norm(env.world.object("bar").position - task.goal(env.world)) < 0.005
    env.close()
