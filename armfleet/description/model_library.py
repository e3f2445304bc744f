"""The arm models armfleet knows: one ``<model>.urdf.xacro`` per model in ``description/``,
any URDF or xacro file given by path (:mod:`~armfleet.description.file_model`), and the
named models of one's own (:mod:`~armfleet.description.own_models`).

The list of models is read from the folder every time, never kept by hand.
Expanding a model gives the URDF of one arm: every link and joint prefixed,
the world anchor placed at the spawn pose, every URI resolved to an absolute
path. The same text feeds PyBullet, Pinocchio and the viewer.
"""

from __future__ import annotations

import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from xml.dom import minidom

import xacro

from armfleet.checks.model_reference import is_model_file
from armfleet.description.data_folders import data_dir
from armfleet.description.end_effector import attach_end_effector
from armfleet.description.file_model import (
    ModelFile,
    anatomy,
    expand_file,
    free_tool0,
    locate,
    wrapper_xacro,
)
from armfleet.description.home_choice import HomeChoice, HomeSource
from armfleet.description.include_cycle import naming_include_cycle
from armfleet.description.model_options import ModelOptions
from armfleet.description.model_problems import refuse_problems
from armfleet.description.own_models import OwnModels
from armfleet.description.package_finder import PackageFinder
from armfleet.description.resource_resolver import ResourceResolver
from armfleet.description.upstream_macro import XACRO_NS, prefixable_macro
from armfleet.errors import DescriptionError, ModelSettingError, UnknownModel
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.physics.clear_home import clear_home
from armfleet.physics.contact_pairs import solid_link_pairs, touching_pairs
from armfleet.physics.lean_urdf import lean_urdf

XACRO_SUFFIX = ".urdf.xacro"
UPSTREAM_PROPERTY = "armfleet_upstream_urdf"
HOME_PROPERTY = "armfleet_home"
#: Unprefixed names of the gripper's joints, space-separated; absent: inferred at run time
#: (the shipped models: their prismatic joints off the arm chain).
GRIPPER_PROPERTY = "armfleet_gripper_joints"
#: Which home a model file got (:class:`~armfleet.description.home_choice.HomeChoice`).
HOME_CHOICE_PROPERTY = "armfleet_home_choice"


@dataclass(frozen=True)
class ArmDescription:
    """The expanded description of one arm.

    Attributes:
        model: model name (the xacro file's stem).
        prefix: prefix of every link and joint, e.g. ``"bob_"``.
        urdf: URDF text with absolute mesh paths.
        home: home positions of the arm joints in chain order [rad or m].
        ignored_contacts: link pairs whose contacts don't count: pairs of links with
            a collision shape never seen touching in random configurations
            (:mod:`armfleet.physics.contact_pairs`).
        gripper_joints: prefixed names of the gripper's joints, as the model file's
            anatomy found them (or as given); empty: the gripper controller infers them
            (the shipped models: prismatic joints off the base-tool chain).
        home_choice: for a model file, which home it got (given, zero or searched);
            None for a shipped model (its file gives it).
    """

    model: str
    prefix: str
    urdf: str
    home: tuple[float, ...]
    ignored_contacts: tuple[tuple[str, str], ...] = ()
    gripper_joints: tuple[str, ...] = ()
    home_choice: HomeChoice | None = None

    @property
    def base_link(self) -> str:
        return f"{self.prefix}base_link"

    @property
    def tool0(self) -> str:
        return f"{self.prefix}tool0"


class ModelLibrary:
    """The models in a description folder.

    Args:
        folder: folder of ``<model>.urdf.xacro`` files; armfleet's own by default.
        resolver: the URI resolver; a default one if omitted.
        package_paths: folders searched first for ROS packages (``package://``,
            ``$(find)``) of model files, as ``--package-path`` gives them.
        own_models: one's own named models; the folders of
            :func:`~armfleet.description.own_models.models_folders` by default.
    """

    def __init__(
        self,
        folder: Path | None = None,
        resolver: ResourceResolver | None = None,
        package_paths: Sequence[str | Path] = (),
        own_models: OwnModels | None = None,
    ):
        self._folder = folder or data_dir("description")
        self._own = own_models or OwnModels()
        self._resolver = resolver or ResourceResolver(finder=PackageFinder(package_paths))
        self._macros: dict[str, str] = {}
        self._templates: dict[str, _Template] = {}
        #: Wrappers written for model files, by model key (see :meth:`path`).
        self._written: dict[str, Path] = {}
        self._scratch: tempfile.TemporaryDirectory[str] | None = None

    @property
    def folder(self) -> Path:
        return self._folder

    @property
    def resolver(self) -> ResourceResolver:
        return self._resolver

    @property
    def names(self) -> list[str]:
        """Model names, sorted, derived from the files in the folder."""
        return sorted(p.name[: -len(XACRO_SUFFIX)] for p in self._folder.glob(f"*{XACRO_SUFFIX}"))

    @property
    def own_models(self) -> OwnModels:
        """One's own named models (``$ARMFLEET_MODELS_PATH`` or the user config folder)."""
        return self._own

    @property
    def available(self) -> list[str]:
        """Every model name: the shipped ones and one's own, sorted."""
        return sorted({*self.names, *self._own.names})

    @property
    def finder(self) -> PackageFinder:
        """Where the ROS packages of model files are found."""
        return self._resolver.finder

    def path(
        self,
        model: str,
        xacro_args: Mapping[str, str] | None = None,
        *,
        options: ModelOptions | None = None,
    ) -> Path:
        """Path of a model's xacro file: a shipped model's, or the wrapper armfleet writes
        for a model file (a ``.urdf``/``.xacro`` path or a ``package://`` URI) or a named
        model of one's own, with ``options`` (and ``xacro_args``) said about it.

        Raises:
            UnknownModel: a name that is no model and no file (every model listed).
            DescriptionError: a model file that cannot be read or expanded, a setting that
                does not fit it, settings for a shipped model, one's own model named like a
                shipped one (one line each).
            PackageNotFound: a package it names is nowhere (every place searched listed).
        """
        arguments = tuple(sorted((str(k), str(v)) for k, v in (xacro_args or {}).items()))
        said = (options or ModelOptions()).merged(ModelOptions(arguments))
        if isinstance(model, str) and is_model_file(model):
            return self._wrapper(model, said)
        names = self.names
        own = self._own.settings_file(model) if isinstance(model, str) else None
        if model in names and own is not None:
            raise DescriptionError(
                f"{own}: {model!r} is a shipped model's name; rename this file (one's own "
                f"models may not shadow the shipped: {', '.join(names)})"
            )
        named = self._own.get(model) if own is not None else None
        if named is not None:
            return self._wrapper(named.file, named.options.merged(said))
        if model not in names:
            raise UnknownModel(model, self.available)
        if not said.is_default:
            raise DescriptionError(
                f"{', '.join(said.given)}: settings of a model file, not of the shipped "
                f"model {model!r}"
            )
        return self._folder / f"{model}{XACRO_SUFFIX}"

    def expand(
        self,
        model: str,
        prefix: str,
        pose: SpawnPose | None = None,
        xacro_args: Mapping[str, str] | None = None,
        *,
        options: ModelOptions | None = None,
    ) -> ArmDescription:
        """Expand ``model`` for an arm whose names start with ``prefix``, placed at ``pose``.

        ``model`` is a shipped model's name, a model file or one's own named model
        (``options`` and ``xacro_args``: what is said about it, :meth:`path`). xacro runs
        once per model with placeholder arguments; each arm is then an instance of that
        text. The first time, a direct expansion with probe arguments must equal the
        instance, else this model is expanded directly every time (a description that
        computes with its arguments).
        """
        pose = pose or SpawnPose()
        path = self.path(model, xacro_args, options=options)  # UnknownModel for no model
        key = str(path)
        template = self._templates.get(key)
        if template is None:
            template = self._make_template(path)
            self._templates[key] = template
        if template.text is None:
            urdf, _ = self._expand_directly(path, prefix, _pose_arguments(pose))
        else:
            urdf = _instantiate(template.text, prefix, pose)
        ignored = tuple((prefix + a, prefix + b) for a, b in template.ignored_contacts)
        gripper = tuple(prefix + joint for joint in template.gripper_joints)
        return ArmDescription(
            model, prefix, urdf, template.home, ignored, gripper, template.home_choice
        )

    def _wrapper(self, model: str, options: ModelOptions) -> Path:
        """The wrapper written for a model file (once per file, arguments and options)."""
        file = ModelFile(locate(model, self.finder), options.xacro_args, options)
        written = self._written.get(file.key)
        if written is not None:
            return written
        with naming_include_cycle(file.path):
            urdf = expand_file(file, self.finder)
        refuse_problems(urdf, str(file.path), self._resolver)  # the world untouched
        source = str(file.path)
        tool_link, gripper = options.tool_link, options.gripper_joints
        if options.end_effector is not None:
            urdf, tool_link, gripper = self._with_end_effector(urdf, source, options)
        found = anatomy(urdf, source, tool_link, gripper, options.home)
        urdf = free_tool0(urdf, found)
        resolved = self._resolver.resolve_text(urdf)
        try:
            home = clear_home(resolved, found.arm_joints, found.home, options.home is None)
        except DescriptionError as exc:
            raise DescriptionError(f"{source}: {exc}") from None
        found = replace(found, home=home.positions)
        if options.home is not None:
            choice = HomeChoice(HomeSource.GIVEN)
        elif home.preferred:
            choice = HomeChoice(HomeSource.ZERO)
        else:
            choice = HomeChoice(HomeSource.SEARCHED, home.reason)
        if self._scratch is None:
            self._scratch = tempfile.TemporaryDirectory(prefix="armfleet-models-")
        folder = Path(self._scratch.name)
        upstream = folder / f"{file.key}.urdf"
        upstream.write_text(urdf)
        wrapper = folder / f"{file.key}{XACRO_SUFFIX}"
        name = _robot_name(urdf, file.path)  # the vendor's, not the wrapper's file name
        wrapper.write_text(wrapper_xacro(name, upstream, found, choice))
        self._written[file.key] = wrapper
        return wrapper

    def _with_end_effector(
        self, urdf: str, source: str, options: ModelOptions
    ) -> tuple[str, str, tuple[str, ...]]:
        """The arm's URDF with its end effector attached, the tool link (the arm's own
        unless ``tool_link`` names another) and the gripper joints (the end effector's
        movable ones unless given)."""
        effector = options.end_effector
        assert effector is not None  # the caller's condition
        arm_links = {link.get("name") for link in ET.fromstring(urdf).iter("link")}
        own_tool = options.tool_link if options.tool_link in arm_links else None
        arm_tool = anatomy(urdf, source, own_tool).tool
        if not effector.file.startswith("package://") and not Path(effector.file).is_file():
            raise ModelSettingError(
                source,
                "end_effector.file",
                f"{effector.file} not found; give a gripper's .urdf or .urdf.xacro",
            )
        path = locate(effector.file, self.finder)
        with naming_include_cycle(path):
            gripper_urdf = expand_file(ModelFile(path, effector.xacro_args), self.finder)
        refuse_problems(gripper_urdf, str(path), self._resolver)
        at_link = effector.at_link or arm_tool
        joined = attach_end_effector(urdf, gripper_urdf, at_link, source, str(path))
        gripper = options.gripper_joints
        tool = options.tool_link or arm_tool
        return joined.urdf, tool, joined.gripper_joints if gripper is None else gripper

    def _make_template(self, path: Path) -> _Template:
        text, properties = self._expand_directly(path, PREFIX_TOKEN, (XYZ_TOKEN, RPY_TOKEN))
        home = _parse_home(path, properties.get(HOME_PROPERTY, ""))
        probe_pose = SpawnPose(0.25, -0.5, 0.125, 30.0, roll_deg=5.0)
        probe, _ = self._expand_directly(path, PROBE_PREFIX, _pose_arguments(probe_pose))
        usable = _instantiate(text, PROBE_PREFIX, probe_pose) == probe
        gripper = tuple(properties.get(GRIPPER_PROPERTY, "").split())
        choice = HomeChoice.parse(properties.get(HOME_CHOICE_PROPERTY, ""))
        return _Template(text if usable else None, home, _never_touching(probe), gripper, choice)

    def _expand_directly(
        self, path: Path, prefix: str, pose_arguments: tuple[str, str]
    ) -> tuple[str, dict[str, str]]:
        """Run xacro; return the URDF (URIs resolved) and the file's top-level properties."""
        model = path.name[: -len(XACRO_SUFFIX)]
        properties = _top_level_properties(path)
        upstream_uri = properties.get(UPSTREAM_PROPERTY)
        if upstream_uri is None:
            raise DescriptionError(f"{path}: missing <xacro:property name={UPSTREAM_PROPERTY!r}>")
        with tempfile.TemporaryDirectory(prefix="armfleet-xacro-") as tmp:
            macro_path = Path(tmp) / f"{model}_upstream.xacro"
            macro_path.write_text(self._upstream_macro(upstream_uri))
            mappings = {
                "prefix": prefix,
                "xyz": pose_arguments[0],
                "rpy": pose_arguments[1],
                "upstream_macro": str(macro_path),
            }
            try:
                document = xacro.process_file(str(path), mappings=mappings)
            except Exception as exc:  # xacro raises bare Exceptions (XacroException, XML errors)
                problem = " ".join(str(exc).split())  # xacro's messages span lines
                raise DescriptionError(f"{path}: xacro failed: {problem}") from exc
            _make_massless_links_explicit(document)
            # The banner names the temporary macro's folder; drop it so texts compare.
            for node in list(document.childNodes):
                if node.nodeType == node.COMMENT_NODE:
                    document.removeChild(node)
            text = document.toprettyxml(indent="  ")
        return self._resolver.resolve_text(text), properties

    def _upstream_macro(self, uri: str) -> str:
        if uri not in self._macros:
            upstream = self._resolver.resolve(uri)
            self._macros[uri] = prefixable_macro(upstream.read_text(), "upstream", str(upstream))
        return self._macros[uri]


#: Prefix of the arm expanded once per model to check the template and sample contacts.
PROBE_PREFIX = "probe_"
#: Placeholders xacro is run with once per model; each arm's values replace them.
PREFIX_TOKEN = "armfleetprefixtoken_"
XYZ_TOKEN = "armfleet-xyz-token"
RPY_TOKEN = "armfleet-rpy-token"


@dataclass(frozen=True)
class _Template:
    """A model expanded with placeholder arguments (``text`` None: can't be templated)."""

    text: str | None
    home: tuple[float, ...]
    ignored_contacts: tuple[tuple[str, str], ...]
    gripper_joints: tuple[str, ...] = ()
    home_choice: HomeChoice | None = None


def _never_touching(probe_urdf: str) -> tuple[tuple[str, str], ...]:
    """Unprefixed pairs of links with a collision shape that no sampled configuration of
    the probe arm brings into contact (see :mod:`armfleet.physics.contact_pairs`)."""
    touching = touching_pairs(lean_urdf(probe_urdf))
    never = sorted(solid_link_pairs(probe_urdf) - touching)
    return tuple((a.removeprefix(PROBE_PREFIX), b.removeprefix(PROBE_PREFIX)) for a, b in never)


def _pose_arguments(pose: SpawnPose) -> tuple[str, str]:
    """The xacro ``xyz`` and ``rpy`` arguments of ``pose``."""
    return (
        f"{pose.x!r} {pose.y!r} {pose.z!r}",
        " ".join(repr(angle) for angle in pose.rpy_rad),
    )


def _instantiate(template: str, prefix: str, pose: SpawnPose) -> str:
    xyz, rpy = _pose_arguments(pose)
    return template.replace(PREFIX_TOKEN, prefix).replace(XYZ_TOKEN, xyz).replace(RPY_TOKEN, rpy)


def _make_massless_links_explicit(document: minidom.Document) -> None:
    """Give every link without ``<inertial>`` (except ``world``) an explicit zero mass.

    URDF means "no mass" by an absent inertial; PyBullet instead invents 1 kg,
    which would make its dynamics disagree with Pinocchio's.
    """
    for link in document.getElementsByTagName("link"):
        if link.getAttribute("name") == "world" or link.getElementsByTagName("inertial"):
            continue
        inertial = document.createElement("inertial")
        mass = document.createElement("mass")
        mass.setAttribute("value", "0")
        inertia = document.createElement("inertia")
        for component in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            inertia.setAttribute(component, "0")
        inertial.appendChild(mass)
        inertial.appendChild(inertia)
        link.appendChild(inertial)


def _top_level_properties(path: Path) -> dict[str, str]:
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise DescriptionError(f"{path} is not valid XML: {exc}") from exc
    return {
        element.get("name", ""): element.get("value", "")
        for element in root.findall(f"{{{XACRO_NS}}}property")
    }


def _parse_home(path: Path, text: str) -> tuple[float, ...]:
    try:
        return tuple(float(v) for v in text.split())
    except ValueError:
        raise DescriptionError(f"{path}: {HOME_PROPERTY} {text!r} must be numbers") from None


def _robot_name(urdf: str, path: Path) -> str:
    """The ``<robot name>`` the file gives (its file name's stem if none), as the arm's
    URDF keeps it: what Foxglove and a recording's ``robot_description`` show."""
    given = ET.fromstring(urdf).get("name") or path.name.split(".")[0]
    return "".join(c if c.isalnum() or c in "_-." else "_" for c in given) or "robot"
