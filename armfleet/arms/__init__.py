"""Arms: the handles users hold, and how an arm is put together.

Owns :class:`~armfleet.arms.arm.Arm`, :class:`~armfleet.arms.gripper.Gripper`, the
assembly of an arm's body, model and controllers (:mod:`~armfleet.arms.arm_assembly`),
and :class:`~armfleet.arms.arm_driver.ArmDriver`, the side of an arm the world's planner
and synchronised motions drive (kept off the user's handle).

Rule: imports the rooms below it (safety, planning, motion, controllers, frames, physics,
...); never the world or a front end.
"""
