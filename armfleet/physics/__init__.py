"""Physics: what PyBullet simulates, and how its state is read and written.

Owns the arm's body (:mod:`~armfleet.physics.arm_body`, its lean URDF
:mod:`~armfleet.physics.lean_urdf`), the floor, link damping, the shared joint memory,
contacts (:mod:`~armfleet.physics.contact_monitor`), which link pairs may touch
(:mod:`~armfleet.physics.contact_pairs`, :mod:`~armfleet.physics.collision_filter`),
whether a start pose is clear (:mod:`~armfleet.physics.start_clearance`), and the quiet
first import of PyBullet.

Rule: the only room that calls PyBullet's stepping and contact queries for the world;
imports :mod:`armfleet.runtime` and below, never a controller, an arm or a front end.
"""
