"""Launch specs: shipped files run, bad specs fail at their line, parameters stay per arm."""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet.cli.spawn_command import spec_from_arguments
from armfleet.controllers.parameters import controller_file, load_parameters
from armfleet.controllers.registry import CONTROLLER_TYPES
from armfleet.description import ModelLibrary
from armfleet.description.data_folders import data_dir
from armfleet.spec import FleetSpec, SpecError, load_spec, parse_spec
from armfleet.world.launch import launch

SHIPPED_SPECS = sorted(data_dir("launch_specs").glob("*.yaml"))
SHIPPED_CONTROLLER_FILES = sorted(data_dir("controllers").glob("*.yaml"))

#: How an unknown-model error lists the choices: every model in description/.
AVAILABLE_MODELS = "available: " + ", ".join(ModelLibrary().names)


def test_every_spec_and_controller_file_is_shipped() -> None:
    assert {p.stem for p in SHIPPED_SPECS} >= {"bob_and_toby", "mixed_cell", "grid_30"}
    assert {p.stem for p in SHIPPED_CONTROLLER_FILES} >= set(CONTROLLER_TYPES)


@pytest.mark.parametrize("path", SHIPPED_SPECS, ids=lambda p: p.stem)
def test_shipped_spec_validates_and_runs(path: Path) -> None:
    spec = load_spec(path)
    world = launch(spec, viewer=False)
    try:
        assert list(world.arms) == [arm.name for arm in spec.arms]
        for arm_spec in spec.arms:
            expected = arm_spec.pose.matrix()
            base = world.tf.lookup("world", f"{arm_spec.name}_base_link")
            assert np.abs(base - expected).max() < 1e-9
        assert list(world.objects) == [o.name for o in spec.objects]
        world.run(0.5)
        for arm in world.arms.values():
            assert arm.position_controller.is_holding, arm.name
        assert world.safety.stops == 0, "no arm touches an object at its home pose"
    finally:
        world.close()


@pytest.mark.parametrize("path", SHIPPED_CONTROLLER_FILES, ids=lambda p: p.stem)
def test_shipped_controller_file_validates_and_runs(path: Path) -> None:
    (controller,) = [name for name in CONTROLLER_TYPES if path.read_text().count(f"{name}:")]
    load_parameters(controller, CONTROLLER_TYPES[controller].parameter_schema, path)
    with armfleet.World() as world:
        arm = world.spawn("bob", parameter_files={controller: path})
        arm.move_to(arm.positions + 0.1)
        world.run(0.5)
        assert arm.position_controller.tracking_error < 1e-3


def test_bob_and_toby_face_each_other() -> None:
    bob, toby = load_spec("bob_and_toby").arms
    assert (bob.pose.x, toby.pose.x) == (0.0, 1.0)
    assert abs(toby.pose.yaw_deg - bob.pose.yaw_deg) == 180.0


def test_grid_30_names_and_spacing() -> None:
    arms = load_spec("grid_30").arms
    assert len(arms) == 30
    assert arms[0].name == "arm0_0" and arms[-1].name == "arm4_5"
    assert (arms[-1].pose.x, arms[-1].pose.y) == (4.0, 5.0)


def spec_text(body: str) -> str:
    return textwrap.dedent(body).strip() + "\n"


BOB = "  - name: bob\n    model: panda\n"
BOX = "  - name: box\n    shape: box\n    size_m: [0.1, 0.1, 0.1]\n    at_m: [2, 0, 0.05]\n"
BAD_SPECS = {
    "yaml syntax": ("world:\n\tdt_s: 0.001\n", 2, "not valid YAML"),
    "unknown top key": ("arm:\n" + BOB, 1, "did you mean 'arms'"),
    "arms not a list": ("arms: {name: bob}\n", 1, "expected a list"),
    "dt out of range": ("world:\n  dt_s: 0.5\narms:\n" + BOB, 2, "outside [1e-05, 0.002]"),
    "dt without unit": ("world:\n  dt: 0.001\n", 2, "did you mean 'dt_s'"),
    "realtime not bool": ("world:\n  realtime: maybe\n", 2, "expected true or false"),
    "missing name": ("arms:\n  - model: panda\n", 2, "arms[0].name: required"),
    "malformed name": ("arms:\n  - name: Bob\n    model: panda\n", 2, "^[a-z][a-z0-9_]*$"),
    "duplicate name": ("arms:\n" + BOB + BOB.replace("  - ", "  - ") + "    at_m: [2, 0]\n", 4,
                       "used twice"),
    "unknown model": ("arms:\n  - name: bob\n    model: pand\n", 3, AVAILABLE_MODELS),
    "yaw without unit": ("arms:\n" + BOB + "    yaw: 90\n", 4, "did you mean 'yaw_deg'"),
    "at wrong length": ("arms:\n" + BOB + "    at_m: [1]\n", 4, "expected 2 or 3 numbers [m]"),
    "two orientations": ("arms:\n" + BOB + "    yaw_deg: 90\n    rpy_deg: [0, 0, 90]\n", 5,
                         "not both yaw_deg and rpy_deg"),
    "overlapping bases": ("arms:\n" + BOB + "  - name: toby\n    model: panda\n"
                          "    at_m: [0.1, 0.05]\n", 6, "toby would touch bob at its start pose"),
    "initial positions length": ("arms:\n" + BOB + "    initial_positions: [0, 0]\n", 4,
                                 "expected 7"),
    "initial position out of limits": (
        "arms:\n" + BOB + "    initial_positions: [0, 0, 0, 0, 0, 1, 0]\n", 4,
        "bob_panda_joint4 is outside its limits",
    ),
    "unknown controller": ("arms:\n" + BOB + "    controllers:\n      velocity_controller: {}\n",
                           5, "valid keys: " + ", ".join(sorted(CONTROLLER_TYPES))),
    "missing controller file": (
        "arms:\n" + BOB + "    controllers:\n      position_controller:\n"
        "        file: nope.yaml\n", 6, "shipped: ",
    ),
    "unknown parameter": (
        "arms:\n" + BOB + "    controllers:\n      position_controller:\n"
        "        parameters: {max_jerk: 5}\n", 6, "did you mean 'max_jerk_rad_s3'",
    ),
    "parameter out of bounds": (
        "arms:\n" + BOB + "    controllers:\n      position_controller:\n"
        "        parameters: {velocity_scaling: 2.0}\n", 6, "outside [0.01, 1]",
    ),
    "grid rows not whole": ("grid:\n  rows: 2.5\n  columns: 2\n  spacing_m: 1\n  model: panda\n",
                            2, "not a whole number"),
    "grid too dense": ("grid:\n  rows: 2\n  columns: 2\n  spacing_m: 0.1\n  model: panda\n", 4,
                       "arm0_1 would touch arm0_0 at its start pose"),
    "object shape unknown": ("objects:\n" + BOX + "  - name: can\n    shape: cilinder\n", 7,
                             "objects[1].shape: unknown shape 'cilinder'; "
                             "valid: box, cylinder, sphere, mesh"),
    "object size length": ("objects:\n  - name: box\n    shape: box\n    size_m: [1, 2]\n", 4,
                           "objects[0].size_m: got 2 numbers; a box takes (x, y, z)"),
    "object size without unit": ("objects:\n  - name: box\n    shape: box\n    size: 1\n", 4,
                                 "did you mean 'size_m'"),
    "object negative mass": ("objects:\n" + BOX + "    mass_kg: -2\n", 6,
                             "objects[0].mass_kg: -2.0 is outside [0, 10000] kg"),
    "object colour length": ("objects:\n" + BOX + "    color_rgba: [1, 0, 0]\n", 6,
                             "expected 4 numbers, got 3"),
    "object mesh missing": ("objects:\n  - name: cup\n    shape: mesh\n    mesh: cup.stl\n", 4,
                            "objects[0].mesh: mesh file '/specs/cup.stl' not found"),
    "object name twice": ("objects:\n" + BOX + BOX, 6, "objects[1].name: object name 'box' "
                          "is used twice"),
    "object named like an arm": ("arms:\n" + BOB + "objects:\n" + BOX.replace("box\n", "bob\n", 1),
                                 5, "objects[0].name: name 'bob' is an arm's"),
    "object name reserved": ("objects:\n" + BOX.replace("box\n", "world\n", 1), 2,
                             "objects[0].name: reserved"),
}  # fmt: skip


@pytest.mark.parametrize("case", BAD_SPECS, ids=list(BAD_SPECS))
def test_bad_spec_gives_file_line_field_and_choices(case: str) -> None:
    text, line, expected = BAD_SPECS[case]
    with pytest.raises(SpecError) as raised:
        parse_spec(text, "cell.yaml", base_dir=Path("/specs"))
    message = str(raised.value)
    print(message)
    assert "\n" not in message
    assert message.startswith(f"cell.yaml:{line}: "), message
    assert expected in message


def test_spec_errors_cover_at_least_twelve_classes() -> None:
    assert len(BAD_SPECS) >= 12


def test_bad_spec_on_the_command_line(tmp_path: Path) -> None:
    import subprocess
    import sys

    bad = tmp_path / "cell.yaml"
    bad.write_text("arms:\n  - name: bob\n    model: pand\n")
    result = subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", "launch", str(bad), "--check"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0
    assert f"{bad}:3: arms[0].model: model 'pand' not found" in result.stderr
    ok = subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", "launch", "grid_30", "--check"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert ok.returncode == 0 and "30 arm(s)" in ok.stdout


def test_parameters_are_per_arm(tmp_path: Path) -> None:
    """toby's file halves the velocity scaling and acceleration: the same move takes
    longer on toby, as Ruckig predicts for each arm, and bob keeps the shipped values."""
    slow = tmp_path / "slow.yaml"
    slow.write_text(
        "position_controller:\n  velocity_scaling: 0.475\n  max_acceleration_rad_s2: 2.5\n"
    )
    spec = parse_spec(
        spec_text(f"""
            world: {{viewer: false}}
            arms:
              - {{name: bob, model: panda, at_m: [0, 0]}}
              - name: toby
                model: panda
                at_m: [1, 0]
                controllers:
                  position_controller: {{file: {slow}}}
        """),
        "per_arm.yaml",
    )
    shipped = load_parameters(
        "position_controller",
        CONTROLLER_TYPES["position_controller"].parameter_schema,
        controller_file("position_controller"),
    )
    world = launch(spec)
    try:
        bob, toby = world.arm("bob"), world.arm("toby")
        assert bob.position_controller.parameters == shipped
        assert toby.position_controller.parameters["velocity_scaling"] == 0.475
        assert toby.position_controller.parameters["max_acceleration_rad_s2"] == 2.5
        durations = {}
        for arm in (bob, toby):
            target = arm.positions + 1.2
            predicted = arm.position_controller.plan(target).duration
            arm.move_to(target)
            start = world.time
            while arm.is_moving:
                world.step()
            durations[arm.name] = (world.time - start, predicted)
        for measured, predicted in durations.values():
            assert abs(measured - predicted) <= 2 * world.dt
        # Jerk-limited profiles don't scale linearly with the limits; measurably longer.
        assert durations["toby"][0] > durations["bob"][0] + 0.3
    finally:
        world.close()


def test_spawn_arguments_and_the_equivalent_spec_give_identical_worlds(tmp_path: Path) -> None:
    args = argparse.Namespace(names=["bob", "toby"], at=["0,0", "1,0,0,180"], model=["panda"])
    from_cli = spec_from_arguments(args, armfleet.World().models)
    from_file = parse_spec(
        spec_text("""
            arms:
              - {name: bob, model: panda, at_m: [0, 0]}
              - {name: toby, model: panda, at_m: [1, 0, 0], yaw_deg: 180}
        """),
        "same.yaml",
    )
    assert from_cli.arms == from_file.arms
    worlds = [launch(FleetSpec(from_file.world, spec.arms), viewer=False)
              for spec in (from_cli, from_file)]  # fmt: skip
    try:
        first, second = worlds
        for name in ("bob", "toby"):
            a, b = first.arm(name), second.arm(name)
            assert a.kinematics.frame_names == b.kinematics.frame_names
            assert a.position_controller.parameters == b.position_controller.parameters
            assert a.broadcaster.parameters == b.broadcaster.parameters
            for frame in a.kinematics.frame_names:
                assert np.abs(first.tf.lookup("world", frame)
                              - second.tf.lookup("world", frame)).max() < 1e-12  # fmt: skip
    finally:
        for world in worlds:
            world.close()


def test_problem_inside_a_controller_file_names_that_file_and_line(tmp_path: Path) -> None:
    params = tmp_path / "mine.yaml"
    params.write_text("position_controller:\n  kp_s2: 900\n  kd: 60\n")
    spec = tmp_path / "cell.yaml"
    spec.write_text(
        "arms:\n  - name: bob\n    model: panda\n    controllers:\n"
        "      position_controller: {file: mine.yaml}\n"
    )
    with pytest.raises(SpecError) as raised:
        load_spec(spec)
    message = str(raised.value)
    assert message.startswith(f"{spec}:4: arms[0].controllers: {params.resolve()}:3: ")
    assert "did you mean 'kd_s'" in message


def test_mixed_cell_has_a_table_between_the_arms_clear_of_them() -> None:
    spec = load_spec("mixed_cell")
    (table,) = spec.objects
    assert table.is_static and table.shape.value == "box"
    picker, placer = (arm.pose.x for arm in spec.arms)
    assert picker < table.at[0] < placer
    with launch(spec, viewer=False) as world:
        world.run(0.5)
        assert world.contacts.touching == {}, "the arms at home touch nothing"
        top = world.tf.lookup("world", "table")[2, 3] + table.size[2] / 2
        assert top == pytest.approx(0.3)


def test_spec_objects_launch_at_their_poses(tmp_path: Path) -> None:
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    obj_text = "".join(f"v {x * 40} {y * 40} {z * 20}\n" for x, y, z in corners)
    obj_text += "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
    (meshes / "block.obj").write_text(obj_text)
    spec_file = tmp_path / "cell.yaml"
    spec_file.write_text(
        spec_text(
            """
            world: {viewer: false}
            arms:
              - {name: bob, model: panda}
            objects:
              - name: table
                shape: box
                size_m: [0.4, 0.6, 0.3]
                mass_kg: 0
                at_m: [0.65, 0, 0.15]
              - {name: can, shape: cylinder, size_m: [0.03, 0.1], at_m: [0.6, 0.1, 0.35],
                 mass_kg: 0.25, friction: 1.2, color_rgba: [0, 0, 1, 1]}
              - {name: ball, shape: sphere, size_m: 0.02, at_m: [-0.5, 0, 0.02]}
              - {name: block, shape: mesh, mesh: meshes/block.obj, scale: 0.001,
                 at_m: [0.6, -0.1, 0.3], yaw_deg: 90, mass_kg: 0.05}
            """
        )
    )
    spec = load_spec(spec_file)
    names = [o.name for o in spec.objects]
    assert names == ["table", "can", "ball", "block"]
    block = spec.objects[3]
    assert block.mesh == (meshes / "block.obj").resolve()
    assert block.size == pytest.approx((0.04, 0.04, 0.02))
    with launch(spec) as world:
        assert list(world.objects) == names
        for obj in spec.objects:
            pose = world.tf.lookup("world", obj.name)
            assert np.abs(pose - obj.matrix()).max() < 1e-9, obj.name
        can = world.object("can")
        assert (can.mass, can.friction, can.color) == (0.25, 1.2, (0.0, 0.0, 1.0, 1.0))
        world.run(0.5)
        # The can and the block stand on the table's top (z = 0.3 m), the ball on the floor.
        assert world.object("can").position[2] == pytest.approx(0.3 + 0.05, abs=1e-3)
        assert world.object("ball").position[2] == pytest.approx(0.02, abs=1e-3)
        assert world.object("block").position[2] == pytest.approx(0.3, abs=3e-3)
        assert world.safety.stops == 0
