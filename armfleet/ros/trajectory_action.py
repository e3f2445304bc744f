"""One arm's joint_trajectory_controller, ROS side: the ``follow_joint_trajectory``
action and the ``joint_trajectory`` topic, under ``/<arm>/joint_trajectory_controller``.

Callbacks run in the ROS executor's threads and hand every message to the world's
stepping thread (``world.submit``), where :class:`~armfleet.ros.trajectory_controller.
TrajectoryController` owns the arm. An invalid goal is accepted and ends at once,
aborted with the controller's error code and a one-line reason (the reason is what a
client can act on; ros2_controllers rejects such a goal without one).
"""

from __future__ import annotations

import contextlib
import logging
import threading
from typing import TYPE_CHECKING, Any

from control_msgs.action import FollowJointTrajectory
from rclpy.action.server import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from armfleet.errors import ArmfleetError
from armfleet.ros.conversions import ros_time
from armfleet.ros.deferred_close import GoalCount, close_when_idle
from armfleet.ros.trajectory_controller import ActiveTrajectory, TrajectoryController
from armfleet.ros.trajectory_goal import INVALID_GOAL, GoalRefused, GoalResult, Outcome

if TYPE_CHECKING:
    from rclpy.action.server import ServerGoalHandle
    from rclpy.node import Node

    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: How often a waiting goal looks at its cancel request [s of wall time].
POLL_S = 0.05


def controller_namespace(arm: str) -> str:
    return f"/{arm}/joint_trajectory_controller"


class _Goal:
    """A goal between the two threads: its entry, and the event its result sets."""

    def __init__(self) -> None:
        self.entry: ActiveTrajectory | None = None
        self.result: GoalResult | None = None
        self.finished = threading.Event()

    def finish(self, result: GoalResult) -> None:
        self.result = result
        self.finished.set()


class TrajectoryAction:
    """The action server and topic of one arm's trajectory controller."""

    def __init__(
        self, node: Node, world: World, controller: TrajectoryController, period_s: float
    ) -> None:
        self._node = node
        self._world = world
        self._controller = controller
        self._period_s = period_s
        self._next_feedback = 0.0
        self._handles: dict[int, ServerGoalHandle[Any, Any, Any]] = {}
        self._goals = GoalCount()
        self._closing = False
        arm = controller.arm.name
        base = controller_namespace(arm)
        self._group = ReentrantCallbackGroup()
        self._server = ActionServer(
            node,
            FollowJointTrajectory,
            f"{base}/follow_joint_trajectory",
            execute_callback=self._execute,
            goal_callback=self._on_goal,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT,
            callback_group=self._group,
        )
        self._topic = node.create_subscription(
            JointTrajectory, f"{base}/joint_trajectory", self._on_topic, 10,
            callback_group=self._group,
        )  # fmt: skip

    def close_goals(self, reason: str) -> None:
        """End the trajectory followed, aborted with ``reason`` (stepping thread)."""
        self._controller.close(reason)

    def close(self) -> threading.Thread:
        """Take the topic down now and the action server once its goals returned (new
        goals are refused meanwhile)."""
        self._closing = True
        self._node.destroy_subscription(self._topic)
        return close_when_idle(self._goals, self._server.destroy)

    # -- stepping thread --------------------------------------------------------------
    @property
    def busy(self) -> bool:
        """Whether a trajectory is waiting or followed (else :meth:`on_step` has nothing
        to do: the server skips it)."""
        return self._controller.active is not None

    def on_step(self, now: float) -> None:
        """Judge the trajectory followed; send feedback at the publication rate."""
        self._controller.on_step(now)
        entry = self._controller.active
        if entry is None or now + 1e-12 < self._next_feedback:
            return
        self._next_feedback = now + self._period_s
        handle = self._handles.get(id(entry))
        sample = self._controller.tracking(now)
        if handle is None or sample is None:
            return
        feedback = FollowJointTrajectory.Feedback()
        feedback.header.stamp = ros_time(now)
        feedback.joint_names = list(self._controller.arm.joint_names)
        feedback.desired = _point(
            sample.desired_position, sample.desired_velocity, sample.desired_acceleration
        )
        feedback.actual = _point(sample.actual_position, sample.actual_velocity)
        feedback.error = _point(
            sample.desired_position - sample.actual_position,
            sample.desired_velocity - sample.actual_velocity,
        )
        handle.publish_feedback(feedback)

    # -- executor threads -------------------------------------------------------------
    def _on_goal(self, _request: Any) -> GoalResponse:
        return GoalResponse.REJECT if self._closing else GoalResponse.ACCEPT

    def _execute(self, handle: ServerGoalHandle[Any, Any, Any]) -> Any:
        with self._goals:
            return self._run(handle)

    def _run(self, handle: ServerGoalHandle[Any, Any, Any]) -> Any:
        goal = _Goal()

        def accept() -> None:
            try:
                goal.entry = self._controller.accept(
                    handle.request.trajectory, self._world.time, handle.request, goal.finish
                )
            except GoalRefused as refused:
                goal.finish(GoalResult(Outcome.ABORTED, refused.error_code, str(refused)))
                return
            self._handles[id(goal.entry)] = handle

        try:
            self._world.submit(accept).result()
        except ArmfleetError as exc:  # the world closed
            goal.finish(GoalResult(Outcome.ABORTED, INVALID_GOAL, str(exc)))
        cancel_sent = False
        while not goal.finished.wait(POLL_S):
            if self._world.closed:
                goal.finish(GoalResult(Outcome.ABORTED, INVALID_GOAL, "the world closed"))
            elif handle.is_cancel_requested and not cancel_sent:
                cancel_sent = self._send_cancel(goal)
        if goal.entry is not None:
            self._handles.pop(id(goal.entry), None)
        result = goal.result
        assert result is not None
        if result.outcome is Outcome.SUCCEEDED:
            handle.succeed()
        elif result.outcome is Outcome.CANCELED and handle.is_cancel_requested:
            handle.canceled()
        else:
            handle.abort()
        return FollowJointTrajectory.Result(
            error_code=result.error_code, error_string=result.error_string
        )

    def _send_cancel(self, goal: _Goal) -> bool:
        """Hand a cancel request to the stepping thread; whether it went."""
        entry = goal.entry
        if entry is None:
            return True
        try:
            self._world.submit(lambda: self._controller.cancel(entry))
        except ArmfleetError:
            return False  # the world is closing: the loop ends the goal
        return True

    def _on_topic(self, message: JointTrajectory) -> None:
        arm = self._controller.arm.name

        def command() -> None:
            try:
                self._controller.accept(message, self._world.time)
            except GoalRefused as refused:
                logger.warning("%s: joint_trajectory refused: %s", arm, refused)

        with contextlib.suppress(ArmfleetError):  # the world is closing
            self._world.submit(command)


def _point(position: Any, velocity: Any, acceleration: Any | None = None) -> JointTrajectoryPoint:
    point = JointTrajectoryPoint()
    point.positions = position.tolist()
    point.velocities = velocity.tolist()
    if acceleration is not None:
        point.accelerations = acceleration.tolist()
    return point
