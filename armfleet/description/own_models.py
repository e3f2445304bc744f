"""Named models of one's own: a folder of ``<name>.yaml`` settings files, each naming a
description file and what to say about it, used by name like a shipped model.

The folders searched, first match first: ``$ARMFLEET_MODELS_PATH`` (``os.pathsep``
separated), else the user's config folder, ``$XDG_CONFIG_HOME/armfleet/models``
(``~/.config/armfleet/models`` by default). A settings file::

    file: my_arm.urdf.xacro        # relative to this file, absolute, or package://...
    xacro_args: {ur_type: ur5e}    # and any setting of armfleet.description.model_options
    tool_link: tool_flange
    home: [0, -1.57, 1.57, 0, 0, 0]

makes ``my_arm`` a model (``world.spawn("bob", model="my_arm")``, ``model: my_arm`` in a
spec, ``armfleet spawn bob --at 0,0 --model my_arm``). A name that is also a shipped
model's is refused in one line when it is used (:class:`~armfleet.description.ModelLibrary`):
a recording or spec naming ``panda`` must mean the same arm everywhere. armfleet only
reads these folders; nothing is written into them or into the installed package.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from armfleet.checks.located_yaml import YamlDocumentError, read_located
from armfleet.description.model_options import SETTING_KEYS, ModelOptions, parse_model_options
from armfleet.errors import DescriptionError, ModelSettingError

MODELS_PATH_ENV = "ARMFLEET_MODELS_PATH"
SETTINGS_SUFFIX = ".yaml"


def models_folders() -> tuple[tuple[Path, ...], str]:
    """The folders of one's own models and where that list came from (for messages)."""
    given = [Path(p).expanduser() for p in os.environ.get(MODELS_PATH_ENV, "").split(os.pathsep)]
    given = [p for p in given if str(p) not in ("", ".")]
    if given:
        return tuple(given), MODELS_PATH_ENV
    config = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return (Path(config).expanduser() / "armfleet" / "models",), "user config folder"


@dataclass(frozen=True)
class OwnModel:
    """A named model of one's own.

    Attributes:
        name: its name (the settings file's stem).
        file: the description file: an absolute path or a ``package://`` URI.
        options: the settings the file gives.
        settings: the settings file.
    """

    name: str
    file: str
    options: ModelOptions
    settings: Path


class OwnModels:
    """The named models in one's models folders (read each time they are asked for).

    Args:
        folders: the folders, first match first; :func:`models_folders` by default.
    """

    def __init__(self, folders: Sequence[Path] | None = None) -> None:
        if folders is None:
            self._folders, self._origin = models_folders()
        else:
            self._folders, self._origin = tuple(Path(f) for f in folders), "given"

    @property
    def folders(self) -> tuple[Path, ...]:
        return self._folders

    @property
    def searched(self) -> str:
        """E.g. ``/home/me/.config/armfleet/models (user config folder)``."""
        return f"{os.pathsep.join(str(f) for f in self._folders)} ({self._origin})"

    @property
    def names(self) -> list[str]:
        """Names of the settings files in the folders, sorted."""
        return sorted(
            {
                path.name[: -len(SETTINGS_SUFFIX)]
                for folder in self._folders
                if folder.is_dir()
                for path in folder.glob(f"*{SETTINGS_SUFFIX}")
                if path.is_file()
            }
        )

    def settings_file(self, name: str) -> Path | None:
        """The settings file of ``name`` (the first folder's), or None."""
        for folder in self._folders:
            path = folder / f"{name}{SETTINGS_SUFFIX}"
            if path.is_file():
                return path
        return None

    def get(self, name: str) -> OwnModel | None:
        """The model ``name``, read from its settings file now; None if there is none.

        Raises:
            DescriptionError: the file is not YAML (its line named).
            ModelSettingError: an unknown key or a bad value (the file and key named).
        """
        path = self.settings_file(name)
        if path is None:
            return None
        try:
            values = read_located(path)
        except YamlDocumentError as exc:
            raise DescriptionError(f"{path}:{exc.line}: {exc.problem}") from None
        if not isinstance(values, dict):
            raise DescriptionError(
                f"{path}: a model's settings are a mapping with file: and any of "
                f"{', '.join(SETTING_KEYS)}"
            )
        options = parse_model_options(values, str(path), path.parent, other_keys=("file",))
        if "file" not in values:
            raise ModelSettingError(
                str(path), "file", "missing: the model's .urdf or .urdf.xacro, relative to here"
            )
        file = values["file"]
        if not isinstance(file, str) or not file.strip():
            raise ModelSettingError(str(path), "file", "expected the path of a .urdf or .xacro")
        if not file.startswith("package://"):
            located = Path(file).expanduser()
            located = located if located.is_absolute() else path.parent / located
            if not located.is_file():
                raise ModelSettingError(str(path), "file", f"{located} not found")
            file = str(located.resolve())
        return OwnModel(name, file, options, path)
