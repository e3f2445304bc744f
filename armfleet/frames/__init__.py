"""Frames: where things are, as ROS's TF tree says it.

Owns the spawn pose (``world -> <arm>_base_link``, :mod:`~armfleet.frames.spawn_pose`),
transform look-ups (:mod:`~armfleet.frames.tf_tree`), the rule that every frame has one
owner (:mod:`~armfleet.frames.frame_registry`) and each arm's robot state publisher
(``/tf``, ``/tf_static``).

Rule: imports :mod:`armfleet.kinematics`, :mod:`armfleet.runtime` and below; scene objects
are seen through the :class:`~armfleet.frames.tf_tree.PosedFrame` protocol.
"""
