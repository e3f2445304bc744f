"""Read a launch spec (YAML) into a :class:`FleetSpec`, checking every field.

Format (all keys but ``name`` and ``model`` optional; units in the key names)::

    world: {dt_s: 0.001, gravity_m_s2: 9.81, realtime: true, viewer: true}
    arms:
      - name: bob
        model: panda               # or my_arm (one's own), or {file: arm.urdf.xacro,
                                   # xacro_args, tool_link, gripper_joints, home, end_effector}
        at_m: [0, 0, 0]            # x, y[, z] of <name>_base_link [m]
        yaw_deg: 0                 # or yaw_rad, rpy_deg: [r, p, y], rpy_rad
        initial_positions: [...]   # arm joints [rad or m]; the model's home if absent
        controllers:
          position_controller:
            file: position_controller.yaml   # next to the spec, else in controllers/
            parameters: {max_acceleration_rad_s2: 3.0}
    grid:                          # R x C arms named arm<row>_<col>, rows along x
      rows: 5
      columns: 6
      spacing_m: 1.0
      model: panda
      origin_m: [0, 0, 0]
      yaw_deg: 0
      controllers: {...}
    objects:                       # added after the arms; see armfleet.spec.object_entries
      - {name: table, shape: box, size_m: [0.8, 0.6, 0.4], mass_kg: 0, at_m: [0.6, 0, 0.2]}
    sweep: {...}                   # read by armfleet.sweeps (docs/sweeps.md), not by launch
"""

from __future__ import annotations

import math
from pathlib import Path

from armfleet.checks.located_yaml import LocatedDict, YamlDocumentError, load_located, read_located
from armfleet.checks.time_step import MAX_DT_S, MIN_DT_S
from armfleet.checks.user_paths import file_problem, given_path
from armfleet.controllers.parameters import check_parameter
from armfleet.controllers.registry import CONTROLLER_TYPES
from armfleet.description import ModelLibrary
from armfleet.description.data_folders import data_dir
from armfleet.description.model_options import SETTING_KEYS, ModelOptions, parse_model_options
from armfleet.errors import ModelSettingError, ParameterError
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.spec.fleet_checks import check_fleet
from armfleet.spec.fleet_spec import ArmSpec, ControllerConfig, FleetSpec, WorldSpec
from armfleet.spec.object_entries import read_objects
from armfleet.spec.scene_rehearsal import LocatedRehearsal
from armfleet.spec.spec_error import SpecError
from armfleet.spec.spec_reader import SpecReader

TOP_KEYS = ("world", "arms", "grid", "objects", "sweep")
WORLD_KEYS = ("dt_s", "gravity_m_s2", "realtime", "viewer")
ORIENTATION_KEYS = ("yaw_deg", "yaw_rad", "rpy_deg", "rpy_rad")
#: Keys of a ``model:`` that names a file: ``file`` and its settings.
MODEL_FILE_KEYS = ("file", *SETTING_KEYS)
ARM_KEYS = ("name", "model", "at_m", "initial_positions", "controllers", *ORIENTATION_KEYS)
GRID_KEYS = ("rows", "columns", "spacing_m", "model", "origin_m", "controllers", "yaw_deg")
CONTROLLER_KEYS = ("file", "parameters")
MAX_GRID_ARMS = 400


def find_spec(name_or_path: str) -> Path:
    """A spec file by path, or by name among the shipped ``launch_specs/``."""
    path = given_path(name_or_path, "launch spec")
    shipped = data_dir("launch_specs")
    names = sorted(p.stem for p in shipped.glob("*.yaml"))
    listed = ", ".join(names) or "(none)"
    problem = file_problem(path)
    if problem is None:
        return path
    for candidate in (shipped / name_or_path, shipped / f"{name_or_path}.yaml"):
        if file_problem(candidate) is None:
            return candidate
    if problem == "not found":
        raise SpecError(name_or_path, 0, "", f"no such spec file; shipped specs: {listed}")
    problem = f"{problem}; give a spec file (.yaml) or a shipped spec's name: {listed}"
    raise SpecError(name_or_path, 0, "", problem)


def load_spec(name_or_path: str | Path) -> FleetSpec:
    """Read and check a launch spec; raise :class:`SpecError` at the first problem."""
    path = find_spec(str(name_or_path))
    try:
        document = read_located(path)
    except YamlDocumentError as exc:
        raise SpecError(exc.source, exc.line, "", exc.problem) from None
    return _spec_from(document, str(path), path.parent)


def parse_spec(text: str | bytes, source: str, base_dir: Path | None = None) -> FleetSpec:
    """Check ``text`` (YAML; bytes must be UTF-8) as a launch spec from ``source``.

    Raises:
        SpecError: at the first problem, with its line (see :mod:`armfleet.checks.located_yaml`
            for the bounds on size, nesting and aliases).
    """
    try:
        document = load_located(text, source)
    except YamlDocumentError as exc:
        raise SpecError(exc.source, exc.line, "", exc.problem) from None
    return _spec_from(document, source, base_dir)


def _spec_from(document: object, source: str, base_dir: Path | None) -> FleetSpec:
    reader = SpecReader(source)
    if document is None:
        document = LocatedDict()
        document.line, document.key_lines = 1, {}
    top = reader.mapping(document, "", 1)
    reader.only_keys(top, "", TOP_KEYS)
    world = _world(reader, top)
    arms: list[tuple[ArmSpec, LocatedDict, str]] = []
    if "arms" in top:
        listed = reader.sequence(top["arms"], "arms", top.line_of("arms"))
        for index, item in enumerate(listed):
            field = f"arms[{index}]"
            entry = reader.mapping(item, field, listed.line_of(index))
            arms.append((_arm(reader, entry, field, base_dir), entry, field))
    if "grid" in top:
        grid = reader.mapping(top["grid"], "grid", top.line_of("grid"))
        arms.extend(_grid(reader, grid, base_dir))
    models = ModelLibrary()
    check_fleet(reader, arms, models)
    names = {arm.name for arm, _, _ in arms}
    with LocatedRehearsal(reader, models) as scene:  # frame owners, clearance
        for arm, entry, field in arms:
            scene.add_arm(arm, entry, field)
        objects = read_objects(reader, top, base_dir, names, _orientation, scene.add_object)
        scene.place_arms()
    return FleetSpec(world, tuple(arm for arm, _, _ in arms), source, objects)


def _world(reader: SpecReader, top: LocatedDict) -> WorldSpec:
    if "world" not in top:
        return WorldSpec()
    world = reader.mapping(top["world"], "world", top.line_of("world"))
    reader.only_keys(world, "world", WORLD_KEYS)
    defaults = WorldSpec()
    return WorldSpec(
        dt_s=reader.number(world, "dt_s", "world", defaults.dt_s, MIN_DT_S, MAX_DT_S, "s"),
        gravity_m_s2=reader.number(
            world, "gravity_m_s2", "world", defaults.gravity_m_s2, -100.0, 100.0, "m/s^2"
        ),
        realtime=reader.boolean(world, "realtime", "world", defaults.realtime),
        viewer=reader.boolean(world, "viewer", "world", defaults.viewer),
    )


def _arm(reader: SpecReader, entry: LocatedDict, field: str, base_dir: Path | None) -> ArmSpec:
    reader.only_keys(entry, field, ARM_KEYS)
    name = reader.text(entry, "name", field)
    model, options = _model(reader, entry, field, base_dir)
    at = reader.numbers(entry, "at_m", field, (2, 3), "m") if "at_m" in entry else (0.0, 0.0)
    roll, pitch, yaw = _orientation(reader, entry, field)
    initial = None
    if "initial_positions" in entry:
        initial = reader.numbers(entry, "initial_positions", field, range(1, 64), "rad or m")
    pose = SpawnPose(*at, yaw_deg=yaw, roll_deg=roll, pitch_deg=pitch)  # type: ignore[misc]
    controllers = _controllers(reader, entry, field, base_dir)
    return ArmSpec(name, model, pose, initial, controllers, options)


def _model(
    reader: SpecReader, entry: LocatedDict, field: str, base_dir: Path | None
) -> tuple[str, ModelOptions]:
    """``model: panda`` (a shipped model or one's own), or ``model: {file: arm.urdf.xacro,
    xacro_args: {...}, tool_link: ..., ...}`` (a file relative to the spec, or a
    ``package://`` URI, and its settings: :mod:`armfleet.description.model_options`)."""
    if "model" not in entry or not isinstance(entry["model"], LocatedDict):
        return reader.text(entry, "model", field), ModelOptions()
    where = f"{field}.model"
    given = reader.mapping(entry["model"], where, entry.line_of("model"))
    reader.only_keys(given, where, MODEL_FILE_KEYS)
    file = reader.text(given, "file", where)
    if not file.startswith("package://"):
        path = Path(file).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        file = str(path.absolute())
    try:
        options = parse_model_options(given, where, base_dir, other_keys=("file",))
    except ModelSettingError as exc:
        key = exc.key.split(".")[0]
        raise reader.error(given.line_of(key), f"{where}.{exc.key}", exc.problem) from None
    return file, options


def _orientation(reader: SpecReader, entry: LocatedDict, field: str) -> tuple[float, float, float]:
    """(roll, pitch, yaw) [deg] from at most one of the orientation keys."""
    given = [key for key in ORIENTATION_KEYS if key in entry]
    if len(given) > 1:
        raise reader.error(
            entry.line_of(given[1]),
            f"{field}.{given[1]}",
            f"give one orientation, not both {given[0]} and {given[1]}",
        )
    if not given:
        return 0.0, 0.0, 0.0
    key = given[0]
    to_deg = math.degrees if key.endswith("_rad") else float
    if key.startswith("yaw"):
        return 0.0, 0.0, to_deg(reader.number(entry, key, field, unit=key[4:]))
    roll, pitch, yaw = reader.numbers(entry, key, field, (3,), key[4:])
    return to_deg(roll), to_deg(pitch), to_deg(yaw)


def _controllers(
    reader: SpecReader, entry: LocatedDict, field: str, base_dir: Path | None
) -> dict[str, ControllerConfig]:
    if "controllers" not in entry:
        return {}
    where = f"{field}.controllers"
    section = reader.mapping(entry["controllers"], where, entry.line_of("controllers"))
    reader.only_keys(section, where, CONTROLLER_TYPES)
    configs = {}
    for controller, raw in section.items():
        path = f"{where}.{controller}"
        config = reader.mapping(raw, path, section.line_of(controller))
        reader.only_keys(config, path, CONTROLLER_KEYS)
        file = None
        if "file" in config:
            file = _controller_file(reader, config, path, base_dir)
        parameters: dict[str, float] = {}
        if "parameters" in config:
            where = f"{path}.parameters"
            given = reader.mapping(config["parameters"], where, config.line_of("parameters"))
            schema = CONTROLLER_TYPES[controller].parameter_schema
            for key, value in given.items():
                try:
                    parameters[key] = check_parameter(controller, schema, key, value)
                except ParameterError as exc:
                    raise reader.error(given.line_of(key), f"{where}.{key}", str(exc)) from None
        configs[controller] = ControllerConfig(file, parameters)
    return configs


def _controller_file(
    reader: SpecReader, config: LocatedDict, field: str, base_dir: Path | None
) -> Path:
    name = reader.text(config, "file", field)
    candidates = [Path(name)] if Path(name).is_absolute() else []
    if base_dir is not None:
        candidates.append(base_dir / name)
    candidates.append(data_dir("controllers") / name)
    for candidate in candidates:
        problem = file_problem(candidate)
        if problem is None:
            return candidate.resolve()
        if problem != "not found":  # found, but no file to read: say so, not "not found"
            raise reader.error(
                config.line_of("file"), f"{field}.file", f"controller file {name!r} {problem}"
            )
    shipped = sorted(p.name for p in data_dir("controllers").glob("*.yaml"))
    raise reader.error(
        config.line_of("file"),
        f"{field}.file",
        f"controller file {name!r} not found next to the spec or in controllers/ "
        f"(shipped: {', '.join(shipped)})",
    )


def _grid(
    reader: SpecReader, grid: LocatedDict, base_dir: Path | None
) -> list[tuple[ArmSpec, LocatedDict, str]]:
    reader.only_keys(grid, "grid", GRID_KEYS)
    rows = reader.number(grid, "rows", "grid", lower=1, upper=MAX_GRID_ARMS)
    columns = reader.number(grid, "columns", "grid", lower=1, upper=MAX_GRID_ARMS)
    for key, value in (("rows", rows), ("columns", columns)):
        if value != int(value):
            raise reader.error(grid.line_of(key), f"grid.{key}", f"{value} is not a whole number")
    if rows * columns > MAX_GRID_ARMS:
        raise reader.error(
            grid.line, "grid", f"{int(rows * columns)} arms is more than {MAX_GRID_ARMS}"
        )
    spacing = reader.number(grid, "spacing_m", "grid", lower=0.0, upper=100.0, unit="m")
    model = reader.text(grid, "model", "grid")
    origin = (0.0, 0.0, 0.0)
    if "origin_m" in grid:
        given = reader.numbers(grid, "origin_m", "grid", (2, 3), "m")
        origin = (given[0], given[1], given[2] if len(given) == 3 else 0.0)
    yaw = reader.number(grid, "yaw_deg", "grid", 0.0, unit="deg")
    controllers = _controllers(reader, grid, "grid", base_dir)
    return [
        (
            ArmSpec(
                f"arm{row}_{column}",
                model,
                SpawnPose(origin[0] + row * spacing, origin[1] + column * spacing, origin[2], yaw),
                None,
                controllers,
            ),
            grid,
            f"grid[arm{row}_{column}]",
        )
        for row in range(int(rows))
        for column in range(int(columns))
    ]
