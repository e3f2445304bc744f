"""The order the test files start in: the slowest first.

``scripts/test.sh`` runs the suite with ``--dist loadfile``: each file goes whole to one
of three workers, the next file to whichever worker runs short. By default xdist starts
the files with the most tests first, which leaves the files of a few long tests (Ray
sweeps, benchmarks, examples, CLI runs against a live world) for the end, where one
worker runs them alone while the others have finished. Started first, the long files
run beside each other and the many short ones fill in at the end.

The figures below only rank the files; a file not listed starts after them, files with
more tests first, as xdist would. A file that grows slow belongs in the list.
"""

from __future__ import annotations

from collections import Counter

import pytest

#: Seconds a file took, roughly (two workers on two cores), for the files over ~10 s. The
#: Ray sweeps (sweep_*) are kept apart, so that the workers seldom run two at once.
SLOW_FILES = {
    # On a fresh clone the wheel test compiles the fleet kernel again (67 s in CI): last,
    # it was the run's tail.
    "test_description.py": 75,
    "test_readme.py": 61,
    "test_recover.py": 60,
    "test_recording_meshes.py": 11,
    "test_envs.py": 53,
    "test_ros_trajectories.py": 60,
    "test_ros_bad_messages.py": 20,
    "test_ros_loopback.py": 7,
    "test_ros_topics.py": 10,
    "test_ros_status.py": 10,
    "test_ros_arms_coming_and_going.py": 15,
    "test_docs_envs_snippets.py": 45,
    "test_envs_sb3.py": 15,
    "test_envs_flat.py": 12,
    "test_envs_reset.py": 30,
    "test_cli_manipulation.py": 51,
    "test_bad_input_cli.py": 45,
    "test_cli_help_and_status.py": 45,
    "test_fleet_update.py": 35,
    "test_bad_input_names.py": 34,
    "test_viewer_browser.py": 30,
    "test_replay_waits.py": 50,
    "test_viewer_loading.py": 22,
    "test_replay.py": 20,
    "test_benchmarks.py": 30,
    "test_cartesian.py": 28.5,
    "test_docs_planning_commands.py": 40,
    "test_self_touching_targets.py": 17,
    "test_cli_output_details.py": 16,
    "test_sweep_cli.py": 28,
    "test_sweep_task_files.py": 30,
    "test_sweep_output_path.py": 23,
    "test_sweep_time_limit.py": 19,
    "test_cli_startup.py": 60,
    "test_continuous_joints.py": 25,
    "test_own_robot.py": 25,
    "test_cli_planning.py": 25,
    "test_shared_cell_example.py": 23,
    "test_planning.py": 22,
    "test_sweep_ray.py": 21,
    "test_own_robot_front_ends.py": 20.5,
    "test_start_clearance.py": 20.4,
    "test_shared_world_fairness.py": 30,
    "test_remote_planning.py": 18.5,
    "test_handover.py": 18,
    "test_remote_session.py": 17.6,
    "test_envs_tasks.py": 17.3,
    "test_bad_input_spec.py": 16.8,
    "test_sweep_faults.py": 16,
    "test_bad_input_adversary.py": 15.7,
    "test_model_options.py": 15.5,
    "test_recording_schemas.py": 15,
    "test_topic_removal.py": 14.7,
    "test_models.py": 14.3,
    "test_plan_display.py": 14,
    "test_recording_cli.py": 13,
    "test_safety.py": 13,
    "test_sweep_cluster.py": 12,
    "test_cli.py": 12,
}


def slowest_files_first(items: list[pytest.Item]) -> None:
    """Sort ``items`` in place, file by file: the listed files by their seconds, then the
    others by their number of tests; a file's own tests keep their order."""
    tests = Counter(item.path.name for item in items)

    def key(item: pytest.Item) -> tuple[float, int]:
        return (-SLOW_FILES.get(item.path.name, 0), -tests[item.path.name])

    items.sort(key=key)  # stable: ties (a file's own tests, equal files) keep their order
