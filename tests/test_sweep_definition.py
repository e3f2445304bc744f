"""A sweep's definition: distributions, targets and their checks, and what a draw changes.

No Ray here: these are the checks made before anything starts, and the pure functions a
worker runs. The draws are checked against numpy's own generators and the spec's values.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from armfleet.controllers.position_controller import PositionController
from armfleet.spec import SpecError, load_spec
from armfleet.sweeps.definition import load_sweep, shipped_scenarios
from armfleet.sweeps.distributions import DistributionError, parse_distribution
from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.randomization import RandomParameter, TargetError, apply_draws, check_target
from armfleet.sweeps.results_file import ResultsWriter
from armfleet.sweeps.results_schema import SweepMetadata
from armfleet.sweeps.sweep import sweep

TASK = "armfleet.scenarios.handover:handover"


def write_sweep(folder: Path, randomize: str = "", extra: str = "", task: str = TASK) -> Path:
    path = folder / "cell.yaml"
    path.write_text(
        f"spec: handover\ntask: {task}\n{extra}" + (f"randomize:\n{randomize}" if randomize else "")
    )
    return path


def test_the_shipped_scenarios_are_the_specs_with_a_sweep_section() -> None:
    assert {"handover", "reach", "crossing"} <= set(shipped_scenarios())
    assert "bob_and_toby" not in shipped_scenarios()


def test_uniform_vectors_stay_in_their_box_and_follow_numpy() -> None:
    distribution, relative = parse_distribution({"uniform": [[-1, 0], [1, 2]]})
    assert not relative and distribution.size == 2
    draws = np.array([distribution.draw(np.random.default_rng(s)) for s in range(500)])
    assert np.all(draws >= [-1, 0]) and np.all(draws < [1, 2])
    assert abs(draws[:, 0].mean()) < 0.1 and abs(draws[:, 1].mean() - 1) < 0.1
    # the same numbers numpy draws from the same generator
    expected = np.random.default_rng(7).uniform([-1, 0], [1, 2])
    assert distribution.draw(np.random.default_rng(7)) == tuple(expected)


def test_integers_include_both_ends_and_choice_picks_only_its_values() -> None:
    integers, _ = parse_distribution({"integers": [2, 4]})
    seen = {integers.draw(np.random.default_rng(s)) for s in range(200)}
    assert seen == {2, 3, 4} and integers.is_integer
    choice, _ = parse_distribution({"choice": [0.05, 0.07]})
    assert {choice.draw(np.random.default_rng(s)) for s in range(50)} == {0.05, 0.07}


def test_a_clipped_normal_never_leaves_its_clip() -> None:
    normal, _ = parse_distribution({"normal": [0.0, 10.0], "clip": [-1, 1]})
    draws = [normal.draw(np.random.default_rng(s)) for s in range(200)]
    assert min(draws) == -1.0 and max(draws) == 1.0  # std 10: both ends are hit
    assert normal.support() == (np.array([-1.0]), np.array([1.0]))


@pytest.mark.parametrize(
    ("entry", "words"),
    [
        ({"uniform": [1, 0]}, "above high"),
        ({"uniform": [0]}, "[low, high]"),
        ({"uniform": [[0, 0], [1]]}, "as many numbers"),
        ({"uniform": [0, float("nan")]}, "not a finite number"),
        ({"normal": [0, -1]}, "standard deviation"),
        ({"gaussian": [0, 1]}, "unknown key 'gaussian'"),
        ({"uniform": [0, 1], "choice": [1]}, "exactly one"),
        ({"uniform": [0, 1], "clip": [0, 1]}, "clip applies to normal only"),
        ({"choice": []}, "non-empty"),
        ({"integers": [0.5, 2]}, "whole numbers"),
        ([0, 1], "a mapping"),
    ],
)
def test_a_badly_written_distribution_is_refused(entry: object, words: str) -> None:
    with pytest.raises(DistributionError, match=words.replace("[", r"\[").replace("]", r"\]")):
        parse_distribution(entry)


def parameter(target: str, entry: object) -> RandomParameter:
    distribution, relative = parse_distribution(entry)
    return RandomParameter(target, distribution, relative)


def test_targets_name_what_the_spec_has() -> None:
    spec = load_spec("handover")
    keywords = {"tolerance_m"}
    for target, entry, words in [
        ("objects.box.at_m", {"uniform": [0, 1]}, "no object 'box'; its objects: pick_table"),
        ("arms.ned.yaw_deg", {"uniform": [0, 1]}, "no arm 'ned'; its arms: bob, toby"),
        ("objects.bar.colour", {"uniform": [0, 1]}, "unknown object field"),
        ("task.speed", {"uniform": [0, 1]}, "no keyword 'speed'; its keywords: tolerance_m"),
        ("robots.bob.at_m", {"uniform": [0, 1]}, "targets start with arms, objects"),
        ("objects.bar.at_m", {"uniform": [0, 1]}, "2 or 3 numbers"),
        ("objects.bar.mass_kg", {"uniform": [-0.1, 0.1]}, "outside the valid range [0, 10000]"),
        (
            "arms.bob.controllers.position_controller.kp_gain",
            {"uniform": [0, 1]},
            "no numeric parameter 'kp_gain'",
        ),
        (
            "arms.bob.controllers.position_controller.protective_stop",
            {"uniform": [0, 1]},
            "no numeric parameter 'protective_stop'",
        ),
    ]:
        with pytest.raises(TargetError, match=re.escape(words)):
            check_target(parameter(target, entry), spec, keywords)


def test_a_controller_parameter_must_stay_inside_its_schema() -> None:
    spec = load_spec("handover")
    schema = {p.name: p for p in PositionController.parameter_schema}
    velocity = schema["velocity_scaling"]  # (0, 1]: from the controller's own schema
    target = "arms.bob.controllers.position_controller.velocity_scaling"
    inside = parameter(target, {"uniform": [0.5, velocity.upper]})
    check_target(inside, spec, set())
    outside = parameter(target, {"uniform": [0.5, velocity.upper + 0.1]})
    with pytest.raises(TargetError, match="outside the valid range"):
        check_target(outside, spec, set())
    unbounded = parameter(target, {"normal": [0.5, 0.1]})  # a normal reaches any value
    with pytest.raises(TargetError, match="add clip"):
        check_target(unbounded, spec, set())
    # relative: the spec's value (the shipped file's 0.95) plus the offset must fit
    with pytest.raises(TargetError, match="with the spec's value added"):
        check_target(parameter(target, {"uniform": [0, 0.1], "relative": True}), spec, set())


def test_a_draw_changes_the_spec_as_written() -> None:
    spec = load_spec("handover")
    bar = next(o for o in spec.objects if o.name == "bar")
    offset = parameter(
        "objects.bar.at_m", {"uniform": [[-0.03, -0.03], [0.03, 0.03]], "relative": True}
    )
    yaw = parameter("arms.toby.yaw_deg", {"uniform": [170, 190]})
    gain = parameter("arms.bob.controllers.position_controller.kp_s2", {"uniform": [1000, 3000]})
    count = parameter("task.tolerance_m", {"choice": [0.01, 0.02]})
    draws = [(p, p.draw(11)) for p in (offset, yaw, gain, count)]
    changed, keywords = apply_draws(spec, draws)
    moved = next(o for o in changed.objects if o.name == "bar")
    dx, dy = draws[0][1]  # type: ignore[misc]
    assert moved.at == pytest.approx((bar.at[0] + dx, bar.at[1] + dy, bar.at[2]))
    toby = next(a for a in changed.arms if a.name == "toby")
    assert toby.pose.yaw_deg == draws[1][1] and toby.pose.x == 1.0
    bob = next(a for a in changed.arms if a.name == "bob")
    assert bob.controllers["position_controller"].parameters["kp_s2"] == draws[2][1]
    assert keywords == {"tolerance_m": draws[3][1]}
    assert spec.objects == load_spec("handover").objects  # the original is untouched


def test_each_parameter_draws_from_its_own_stream() -> None:
    """Adding a parameter to a sweep leaves the others' values as they were."""
    a = parameter("objects.bar.mass_kg", {"uniform": [0.1, 0.2]})
    b = parameter("objects.bar.friction", {"uniform": [0.1, 0.2]})
    assert [a.draw(s) for s in range(5)] == [a.draw(s) for s in range(5)]
    assert a.draw(3) != b.draw(3)  # same distribution, another stream
    assert len({a.draw(s) for s in range(20)}) == 20


def test_a_sweep_file_names_its_spec_and_is_checked_at_its_lines(tmp_path: Path) -> None:
    path = write_sweep(
        tmp_path,
        "  objects.bar.mass_kg: {uniform: [0.1, 0.2]}\n  objects.bar.yaw_deg: {uniform: [2, 1]}\n",
    )
    with pytest.raises(SpecError) as error:
        load_sweep(path)
    assert f"{path}:5: randomize.objects.bar.yaw_deg: uniform: low [2.0] is above" in str(
        error.value
    )
    good = write_sweep(tmp_path, "  objects.bar.mass_kg: {uniform: [0.1, 0.2]}\n", "runs: 7\n")
    definition = load_sweep(good)
    assert definition.runs == 7 and definition.parameter_columns == ("objects.bar.mass_kg",)
    assert definition.spec.source.endswith("handover.yaml")


@pytest.mark.parametrize(
    ("task", "words"),
    [
        ("armfleet.scenarios.handover:TOLERANCE_M", "is a float, not a function"),
        ("armfleet.scenarios.handover:nothing", "no 'nothing' in it; its functions:"),
        ("armfleet.no_such_module:task", "cannot import 'armfleet.no_such_module'"),
        ("handover", "give module:function"),
        ("missing.py", "task file 'missing.py' not found"),
    ],
)
def test_a_task_that_is_no_function_is_refused(tmp_path: Path, task: str, words: str) -> None:
    with pytest.raises(SpecError, match=words):
        load_sweep(write_sweep(tmp_path, task=task))


def test_a_task_file_next_to_the_sweep_is_found(tmp_path: Path) -> None:
    (tmp_path / "tasks.py").write_text(
        "def settle(world, rng, *, seconds=0.1):\n"
        "    world.run(seconds)\n"
        "    return {'t': world.time}\n"
        "def needs_more(world):\n"
        "    return {}\n"
    )
    definition = load_sweep(
        write_sweep(tmp_path, "  task.seconds: {uniform: [0.1, 0.2]}\n", task="tasks.py:settle")
    )
    assert definition.task.function == "settle" and definition.task.module is None
    with pytest.raises(SpecError, match="a task takes \\(world, rng\\)"):
        load_sweep(write_sweep(tmp_path, task="tasks.py:needs_more"))


def test_an_unknown_scenario_lists_the_shipped_ones() -> None:
    with pytest.raises(
        SweepError, match=r"unknown scenario: 'handvoer'; shipped scenarios: .*handover"
    ):
        load_sweep("handvoer")
    with pytest.raises(SweepError, match="defines no sweep"):
        load_sweep(load_spec("bob_and_toby").source)


def test_resume_refuses_a_file_of_another_or_a_changed_sweep(tmp_path: Path) -> None:
    """Before anything starts: resuming must not mix runs of two different sweeps."""
    first = load_sweep(write_sweep(tmp_path, "  objects.bar.mass_kg: {uniform: [0.1, 0.2]}\n"))
    results = tmp_path / "r.parquet"
    metadata = SweepMetadata(
        scenario="cell.yaml",
        spec=first.spec.source,
        task=first.task.name,
        base_seed=0,
        runs=3,
        parameters=first.parameter_columns,
        digest=first.digest,
    )
    ResultsWriter(results, metadata).close()
    changed = write_sweep(tmp_path, "  objects.bar.mass_kg: {uniform: [0.1, 0.3]}\n")
    assert load_sweep(changed).digest != first.digest
    with pytest.raises(SweepError, match="holds another sweep"):
        sweep(changed, runs=3, output=results, resume=True)
    with pytest.raises(SweepError, match="exists; --resume runs the seeds it lacks"):
        sweep(changed, runs=3, output=results)
    with pytest.raises(SweepError, match=r"give a \.parquet file"):
        sweep(changed, runs=3, output=tmp_path / "r.csv")
