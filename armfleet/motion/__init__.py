"""Motion: how an arm is asked to move, straight or together with others.

Owns the move options and planning defaults (:mod:`~armfleet.motion.move_options`), the
pose goal (:class:`~armfleet.motion.pose_goal.PoseGoal`), straight Cartesian paths
(:mod:`~armfleet.motion.cartesian_path`) and synchronised motions of several arms
(:mod:`~armfleet.motion.synchronised_motion`, which drives a ``SynchronisedArm``).

Rule: imports :mod:`armfleet.controllers`, :mod:`armfleet.kinematics` and below; never an
arm handle, the planner or the world.
"""
