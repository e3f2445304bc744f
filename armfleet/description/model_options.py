"""What a user says about a model file: its xacro arguments and what armfleet would
otherwise infer (:mod:`~armfleet.description.file_model`).

One value for every surface: ``world.spawn(..., tool_link=...)``, a spec's ``model:``
mapping, ``armfleet spawn --tool-link``, the live API and a named model's settings file
(:mod:`~armfleet.description.own_models`). It is hashable: the wrapper armfleet writes
for a file is keyed by it.

Settings (every one optional)::

    xacro_args: {ur_type: ur5e}       # arguments of a xacro file
    tool_link: wrist_3_link           # the link tool0 is put on
    gripper_joints: [finger_joint]    # movable joints off the arm chain; [] for none
    home: [0, -1.57, 1.57, 0, 0, 0]   # one value per arm joint [rad or m]
    end_effector:                     # a gripper description attached at a link
      file: my_gripper.urdf.xacro     # relative to the settings (spec, settings file)
      at_link: tool0                  # default: the arm's tool link
      xacro_args: {...}
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from armfleet.errors import ModelSettingError

#: Keys of the settings of a model file.
SETTING_KEYS = ("xacro_args", "tool_link", "gripper_joints", "home", "end_effector")
END_EFFECTOR_KEYS = ("file", "at_link", "xacro_args")
#: Most values a ``home`` or ``gripper_joints`` may hold (an arm has at most 63 joints).
MAX_JOINTS = 64

Arguments = tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class EndEffector:
    """A gripper description attached by a fixed joint at a link of the arm.

    Attributes:
        file: an absolute path or a ``package://`` URI of a URDF or xacro file.
        at_link: the arm's link (unprefixed) it hangs from; None: the arm's tool link.
        xacro_args: ``(name, value)`` arguments of its xacro, sorted.
    """

    file: str
    at_link: str | None = None
    xacro_args: Arguments = ()


@dataclass(frozen=True)
class ModelOptions:
    """A model file's xacro arguments and the anatomy the user gives (None: inferred).

    Attributes:
        xacro_args: ``(name, value)`` arguments of the file's xacro, sorted.
        tool_link: the link ``tool0`` is put on.
        gripper_joints: the gripper's joints; ``()``: none.
        home: one value per arm joint, in chain order [rad or m].
        end_effector: a gripper description attached to the arm.
    """

    xacro_args: Arguments = ()
    tool_link: str | None = None
    gripper_joints: tuple[str, ...] | None = None
    home: tuple[float, ...] | None = None
    end_effector: EndEffector | None = field(default=None)

    @property
    def is_default(self) -> bool:
        """Nothing said: the file as it is, with no arguments."""
        return self == ModelOptions()

    @property
    def given(self) -> tuple[str, ...]:
        """The settings given, in :data:`SETTING_KEYS` order."""
        return tuple(key for key in SETTING_KEYS if getattr(self, key) not in (None, ()))

    def merged(self, over: ModelOptions) -> ModelOptions:
        """These settings with ``over``'s given ones on top (xacro arguments merged)."""
        arguments = {**dict(self.xacro_args), **dict(over.xacro_args)}
        return ModelOptions(
            tuple(sorted(arguments.items())),
            over.tool_link if over.tool_link is not None else self.tool_link,
            over.gripper_joints if over.gripper_joints is not None else self.gripper_joints,
            over.home if over.home is not None else self.home,
            over.end_effector if over.end_effector is not None else self.end_effector,
        )

    def keywords(self) -> dict[str, Any]:
        """These settings as the keywords of :meth:`armfleet.World.spawn` (None: not given)."""
        return {
            "xacro_args": dict(self.xacro_args),
            "tool_link": self.tool_link,
            "gripper_joints": self.gripper_joints,
            "home": self.home,
            "end_effector": self.end_effector,
        }

    def to_mapping(self) -> dict[str, Any]:
        """The given settings as plain values (JSON, YAML); :func:`parse_model_options`
        reads them back."""
        out: dict[str, Any] = {}
        if self.xacro_args:
            out["xacro_args"] = dict(self.xacro_args)
        if self.tool_link is not None:
            out["tool_link"] = self.tool_link
        if self.gripper_joints is not None:
            out["gripper_joints"] = list(self.gripper_joints)
        if self.home is not None:
            out["home"] = list(self.home)
        if self.end_effector is not None:
            effector: dict[str, Any] = {"file": self.end_effector.file}
            if self.end_effector.at_link is not None:
                effector["at_link"] = self.end_effector.at_link
            if self.end_effector.xacro_args:
                effector["xacro_args"] = dict(self.end_effector.xacro_args)
            out["end_effector"] = effector
        return out


def parse_model_options(
    values: Mapping[str, Any],
    source: str,
    base_dir: Path | None = None,
    other_keys: tuple[str, ...] = (),
) -> ModelOptions:
    """The settings in ``values`` (see the module docstring); ``other_keys`` are allowed
    and left to the caller (a settings file's ``file``).

    Args:
        source: where the values came from, first in every message.
        base_dir: folder a relative ``end_effector.file`` is relative to; None: the
            working folder.

    Raises:
        ModelSettingError: an unknown key (the valid ones listed) or a bad value, naming
            the key.
    """
    if not isinstance(values, Mapping):
        raise ModelSettingError(source, "model", f"expected a mapping, got {_kind(values)}")
    _only_keys(source, "", values, SETTING_KEYS + other_keys)
    home = values.get("home")
    effector = values.get("end_effector")
    return ModelOptions(
        _arguments(source, "xacro_args", values.get("xacro_args")),
        None if "tool_link" not in values else _name(source, "tool_link", values["tool_link"]),
        None if "gripper_joints" not in values else _names(source, values["gripper_joints"]),
        None if home is None else _home(source, home),
        None if effector is None else _end_effector(source, effector, base_dir),
    )


def options_from_keywords(
    source: str,
    *,
    xacro_args: object = None,
    tool_link: object = None,
    gripper_joints: object = None,
    home: object = None,
    end_effector: object = None,
) -> ModelOptions:
    """The settings given as keywords (``world.spawn(..., tool_link=...)``; None: not
    given), checked as :func:`parse_model_options` checks a mapping; a relative
    ``end_effector`` file is relative to the working folder.

    Raises:
        ModelSettingError: a bad value, naming the keyword.
    """
    if hasattr(home, "tolist"):  # a numpy array
        home = home.tolist()
    if isinstance(end_effector, (str, Path)):  # just the file
        end_effector = {"file": str(end_effector)}
    given = {
        "xacro_args": xacro_args,
        "tool_link": tool_link,
        "gripper_joints": gripper_joints,
        "home": home,
        "end_effector": end_effector,
    }
    return parse_model_options({k: v for k, v in given.items() if v is not None}, source)


def _only_keys(source: str, where: str, values: Mapping[str, Any], valid: tuple[str, ...]) -> None:
    for key in values:
        if key not in valid:
            raise ModelSettingError(
                source, f"{where}{key}", f"unknown setting; valid: {', '.join(valid)}"
            )


def _kind(value: object) -> str:
    return "nothing" if value is None else type(value).__name__


def _name(source: str, key: str, value: object) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ModelSettingError(source, key, f"expected a name, got {_kind(value)}")
    return value.strip()


def _names(source: str, value: object) -> tuple[str, ...]:
    if isinstance(value, str):  # one joint: gripper_joints: finger_joint
        value = [value]
    if not isinstance(value, (list, tuple)) or len(value) > MAX_JOINTS:
        raise ModelSettingError(source, "gripper_joints", "expected a list of joint names")
    names = tuple(_name(source, "gripper_joints", item) for item in value)
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ModelSettingError(source, "gripper_joints", f"{', '.join(repeated)} given twice")
    return names


def _home(source: str, value: object) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or not 0 < len(value) <= MAX_JOINTS:
        raise ModelSettingError(source, "home", "expected a list of joint positions [rad or m]")
    home = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, (int, float)) or not math.isfinite(item):
            raise ModelSettingError(source, "home", f"{item!r} is not a finite number")
        home.append(float(item))
    return tuple(home)


def _arguments(source: str, key: str, value: object) -> Arguments:
    if value is None:
        return ()
    if not isinstance(value, Mapping):
        raise ModelSettingError(
            source, key, f"expected a mapping {{name: value}}, got {_kind(value)}"
        )
    pairs = []
    for name, item in value.items():
        if not isinstance(item, (str, int, float, bool)):
            raise ModelSettingError(source, f"{key}.{name}", "expected text or a number")
        pairs.append((str(name), str(item).lower() if isinstance(item, bool) else str(item)))
    return tuple(sorted(pairs))


def _end_effector(source: str, value: object, base_dir: Path | None) -> EndEffector:
    if isinstance(value, EndEffector):
        return value
    if not isinstance(value, Mapping):
        raise ModelSettingError(
            source, "end_effector", f"expected a mapping with file:, got {_kind(value)}"
        )
    _only_keys(source, "end_effector.", value, END_EFFECTOR_KEYS)
    if "file" not in value:
        raise ModelSettingError(source, "end_effector.file", "missing: the gripper's description")
    file = _name(source, "end_effector.file", value["file"])
    if not file.startswith("package://"):
        path = Path(file).expanduser()
        if not path.is_absolute():
            path = (base_dir or Path.cwd()) / path
        file = str(path.absolute())
    at_link = value.get("at_link")
    return EndEffector(
        file,
        None if at_link is None else _name(source, "end_effector.at_link", at_link),
        _arguments(source, "end_effector.xacro_args", value.get("xacro_args")),
    )
