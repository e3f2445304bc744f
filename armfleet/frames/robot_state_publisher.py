"""Per-arm transforms: static ones on ``/tf_static`` at spawn, moving ones on ``/tf``.

As ROS's robot_state_publisher: one transform per URDF joint, parent link ->
child link, plus ``world -> <arm>_base_link`` carrying the spawn pose.
"""

from __future__ import annotations

import numpy as np

from armfleet import topics
from armfleet.kinematics import ArmKinematics
from armfleet.messages import JointState, TFMessage, TransformStamped
from armfleet.runtime.bus import Bus, Subscription


class RobotStatePublisher:
    """Publishes one arm's transforms.

    Args:
        arm: arm name.
        kinematics: the arm's model.
        bus: the world's bus.
        stamp: simulated time of the spawn [s].
    """

    def __init__(self, arm: str, kinematics: ArmKinematics, bus: Bus, stamp: float) -> None:
        self._arm = arm
        self._kinematics = kinematics
        self._bus = bus
        edges = kinematics.link_edges()
        self._moving = tuple(e for e in edges if not e.fixed)
        bus.advertise(topics.TF, TFMessage)
        bus.advertise(topics.TF_STATIC, TFMessage)
        # The static edges do not depend on q: any configuration gives them.
        kinematics.update(
            np.clip(np.zeros(kinematics.model.nq), kinematics.lower, kinematics.upper)
        )
        static = tuple(self._transform(stamp, e.parent, e.child) for e in edges if e.fixed)
        self.static_message = TFMessage(static)
        bus.publish(topics.TF_STATIC, self.static_message, latch=True)
        self._subscription: Subscription = bus.subscribe(topics.joint_states(arm), self._on_state)

    def _transform(self, stamp: float, parent: str, child: str) -> TransformStamped:
        return TransformStamped(stamp, parent, child, self._kinematics.relative_pose(parent, child))

    def _on_state(self, state: JointState) -> None:
        if not self._bus.has_subscribers(topics.TF):
            return
        self._kinematics.update(state.position)
        self._bus.publish(
            topics.TF,
            TFMessage(tuple(self._transform(state.stamp, e.parent, e.child) for e in self._moving)),
        )

    def close(self) -> None:
        """Stop publishing and withdraw the arm's static transforms."""
        self._subscription.cancel()
        mine = self.static_message
        self._bus.forget_latched(topics.TF_STATIC, lambda message: message is mine)
