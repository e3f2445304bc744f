"""A sweep's definition: a launch spec, a task, fixed task parameters and a randomization.

It is read from a launch spec's ``sweep:`` section, or from a sweep file that names its
spec (``spec: handover`` or a path next to it)::

    sweep:                                    # in a launch spec; a sweep file has these
      task: armfleet.scenarios.handover:handover   # keys at its top, plus spec:
      base_seed: 0                            # run i has seed base_seed + i
      runs: 100                               # default of --runs
      run_timeout_s: 300                      # a run past it fails (its row says so)
      parameters: {tolerance_m: 0.02}         # fixed keyword arguments of the task
      randomize:                              # target: distribution (distributions.py)
        objects.bar.at_m: {uniform: [[-0.03, -0.03, 0], [0.03, 0.03, 0]], relative: true}

Everything is checked when it is read, before any run: an unknown target, a
distribution outside its parameter's range, a task that is not a function of
``(world, rng)`` or lacks a keyword that is set.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from armfleet.checks.located_yaml import LocatedDict, YamlDocumentError, read_located
from armfleet.checks.number_ranges import MAX_SWEEP_RUNS
from armfleet.checks.real_numbers import is_real
from armfleet.checks.user_paths import file_problem, given_path
from armfleet.description.data_folders import data_dir
from armfleet.spec import FleetSpec, SpecError, load_spec
from armfleet.spec.spec_reader import SpecReader
from armfleet.sweeps.distributions import DistributionError, parse_distribution
from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.randomization import RandomParameter, TargetError, check_target
from armfleet.sweeps.task_reference import TaskError, TaskReference, task_keywords, task_reference

SECTION_KEYS = ("task", "base_seed", "runs", "run_timeout_s", "parameters", "randomize")
#: A run that has not ended after this long fails, unless the sweep says otherwise [s].
DEFAULT_RUN_TIMEOUT_S = 600.0
MAX_RUNS = MAX_SWEEP_RUNS
MAX_SEED = 2**62

TaskValue = float | int | bool | str | tuple[float, ...]


@dataclass(frozen=True)
class SweepDefinition:
    """Everything a worker needs to run any seed of the sweep (it is sent to each).

    Attributes:
        scenario: as the user named it.
        spec: the launch spec every run starts from (viewer off in the runs).
        task: the task.
        parameters: fixed keyword arguments of the task.
        randomization: what each run draws.
        base_seed: run i has seed ``base_seed + i``.
        runs: the default number of runs (None: the caller must say).
        run_timeout_s: wall time after which a run fails [s].
    """

    scenario: str
    spec: FleetSpec
    task: TaskReference
    parameters: dict[str, TaskValue] = field(default_factory=dict)
    randomization: tuple[RandomParameter, ...] = ()
    base_seed: int = 0
    runs: int | None = None
    run_timeout_s: float = DEFAULT_RUN_TIMEOUT_S

    @property
    def digest(self) -> str:
        """A fingerprint of what a run depends on (the spec's content, the task's name, its
        parameters, the randomization): a resumed sweep must have the same one."""
        content = repr(
            (
                replace(self.spec, source=""),
                self.task.name,
                self.task.source,
                sorted(self.parameters.items()),
                [(p.target, p.relative, repr(p.distribution)) for p in self.randomization],
                self.base_seed,
            )
        )
        return hashlib.sha256(content.encode()).hexdigest()[:16]

    @property
    def parameter_columns(self) -> tuple[str, ...]:
        """The results' parameter columns, in order."""
        return tuple(column for p in self.randomization for column in p.columns)


def shipped_scenarios() -> list[str]:
    """Names of the shipped launch specs that have a ``sweep:`` section."""
    names = []
    for path in sorted(data_dir("launch_specs").glob("*.yaml")):
        try:
            document = read_located(path)
        except YamlDocumentError:
            continue
        if isinstance(document, LocatedDict) and "sweep" in document:
            names.append(path.stem)
    return names


def load_sweep(scenario: str | Path) -> SweepDefinition:
    """The sweep of a shipped scenario's name, a launch spec with a ``sweep:`` section, or a
    sweep file.

    Raises:
        SweepError: no such scenario or file, or a file that defines no sweep.
        SpecError: a problem in the spec or the sweep section, with its line.
    """
    text = str(scenario)
    path = _scenario_file(text)
    try:
        document = read_located(path)
    except YamlDocumentError as exc:
        raise SpecError(exc.source, exc.line, "", exc.problem) from None
    reader = SpecReader(str(path))
    if not isinstance(document, LocatedDict):
        raise SweepError(f"{path}: not a launch spec or sweep file (expected a mapping)")
    if "sweep" in document:
        spec = load_spec(path)
        section = reader.mapping(document["sweep"], "sweep", document.line_of("sweep"))
        return _definition(text, spec, reader, section, "sweep", path.parent)
    if "spec" in document:
        reader.only_keys(document, "", ("spec", *SECTION_KEYS))
        spec_name = reader.text(document, "spec", "")
        local = path.parent / spec_name
        spec = load_spec(local if file_problem(local) is None else spec_name)
        return _definition(text, spec, reader, document, "", path.parent)
    raise SweepError(
        f"{path} defines no sweep: give a launch spec with a sweep: section or a sweep file "
        f"with spec: and task:; shipped scenarios: {', '.join(shipped_scenarios())}"
    )


def _scenario_file(text: str) -> Path:
    path = given_path(text, "scenario")
    if file_problem(path) is None:
        return path
    shipped = shipped_scenarios()
    if text in shipped:
        return data_dir("launch_specs") / f"{text}.yaml"
    problem = file_problem(path)
    what = "unknown scenario" if problem == "not found" else f"scenario file {problem}"
    raise SweepError(
        f"{what}: {text!r}; shipped scenarios: {', '.join(shipped)} (or a launch spec "
        "with a sweep: section, or a sweep file)"
    )


def _definition(
    scenario: str,
    spec: FleetSpec,
    reader: SpecReader,
    section: LocatedDict,
    where: str,
    base_dir: Path,
) -> SweepDefinition:
    def at(key: str) -> str:
        return f"{where}.{key}" if where else key

    if where:
        reader.only_keys(section, where, SECTION_KEYS)
    if "task" not in section:
        raise reader.error(
            section.line, where or "task", "no task: give module:function or file.py:function"
        )
    line = section.line_of("task")
    try:
        task = task_reference(reader.text(section, "task", where), base_dir)
        keywords = task_keywords(task.load(), task.name)
    except TaskError as exc:
        raise reader.error(line, at("task"), str(exc)) from None
    base_seed = _whole(reader, section, "base_seed", where, 0, 0, MAX_SEED)
    runs = None
    if "runs" in section:
        runs = _whole(reader, section, "runs", where, 1, 1, MAX_RUNS)
    timeout = reader.number(
        section, "run_timeout_s", where, DEFAULT_RUN_TIMEOUT_S, 0.001, 86400.0, "s"
    )
    parameters = _parameters(reader, section, at("parameters"), keywords)
    randomization: list[RandomParameter] = []
    if "randomize" in section:
        given = reader.mapping(section["randomize"], at("randomize"), section.line_of("randomize"))
        for target, entry in given.items():
            field_name = f"{at('randomize')}.{target}"
            try:
                distribution, relative = parse_distribution(entry)
                parameter = RandomParameter(str(target), distribution, relative)
                check_target(parameter, spec, keywords)
            except (DistributionError, TargetError, SweepError) as exc:
                raise reader.error(given.line_of(target), field_name, str(exc)) from None
            randomization.append(parameter)
    return SweepDefinition(
        scenario,
        spec,
        task,
        parameters,
        tuple(randomization),
        base_seed,
        runs,
        timeout,
    )


def _whole(
    reader: SpecReader,
    section: LocatedDict,
    key: str,
    where: str,
    default: int,
    low: int,
    high: int,
) -> int:
    if key not in section:
        return default
    value = section[key]
    if not is_real(value) or float(value) != int(value) or not low <= int(value) <= high:
        raise reader.error(
            section.line_of(key),
            f"{where}.{key}" if where else key,
            f"{value!r} is not a whole number in {low}..{high}",
        )
    return int(value)


def _parameters(
    reader: SpecReader, section: LocatedDict, where: str, keywords: set[str]
) -> dict[str, TaskValue]:
    if "parameters" not in section:
        return {}
    given = reader.mapping(section["parameters"], where, section.line_of("parameters"))
    values: dict[str, TaskValue] = {}
    for key, value in given.items():
        line = given.line_of(key)
        if key not in keywords and "**" not in keywords:
            valid = ", ".join(sorted(keywords - {"**"})) or "none"
            raise reader.error(line, f"{where}.{key}", f"the task takes no {key!r}; its: {valid}")
        values[key] = _task_value(reader, line, f"{where}.{key}", value)
    return values


def _task_value(reader: SpecReader, line: int, where: str, value: Any) -> TaskValue:
    if isinstance(value, bool | str):
        return value
    if is_real(value):
        return int(value) if isinstance(value, int) else float(value)
    if isinstance(value, list) and value and all(is_real(v) for v in value):
        return tuple(float(v) for v in value)
    raise reader.error(line, where, f"{value!r}: give a number, a list of numbers, text or bool")
