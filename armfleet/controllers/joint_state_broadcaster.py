"""joint_state_broadcaster: reads the arm's joints and publishes ``/<arm>/joint_states``."""

from __future__ import annotations

from armfleet.controllers.controller import Controller
from armfleet.controllers.parameters import ParameterSpec
from armfleet.messages import FloatArray, JointState


class JointStateBroadcaster(Controller):
    """Publishes every movable joint of the arm (arm joints and fingers alike)."""

    type_name = "joint_state_broadcaster"
    rate_parameter = "publish_rate_hz"
    parameter_schema = (
        ParameterSpec("publish_rate_hz", 1000.0, "publication rate [Hz]", 1.0, 100_000.0),
    )

    latest: JointState | None = None

    def on_configure(self) -> None:
        self._topic = self.arm.topic("joint_states")
        self._names = self.arm.kinematics.joint_names
        self.arm.bus.advertise(self._topic, JointState)

    def update(self, stamp: float) -> None:
        body = self.arm.body
        self.publish(stamp, body.position.copy(), body.velocity.copy(), body.effort_command.copy())

    def publish(
        self, stamp: float, position: FloatArray, velocity: FloatArray, effort: FloatArray
    ) -> None:
        """Publish a sample of the arm's joints: arrays nobody writes to again (copies)."""
        self.latest = JointState(stamp, self._names, position, velocity, effort)
        self.arm.bus.publish(self._topic, self.latest)
