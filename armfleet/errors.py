"""Errors a user can cause, each naming the problem and the valid choices.

Every error armfleet raises on bad input derives from :class:`ArmfleetError`;
the CLI turns one into a single line on stderr and exit code 2.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence


def _choices(values: Iterable[str]) -> str:
    listed = sorted(values)
    return ", ".join(listed) if listed else "(none)"


#: Longest name or value an error message prints whole (a name may have 64 characters
#: and a frame adds its link's suffix); anything longer is cut, so a message stays one line.
_SHOWN_CHARS = 96


def shown_name(name: object) -> str:
    """``repr(name)``, cut short for anything too long to print on one line."""
    if isinstance(name, str) and len(name) > _SHOWN_CHARS:
        return f"{name[:_SHOWN_CHARS]!r}..."
    shown = repr(name)
    return shown if len(shown) <= _SHOWN_CHARS else f"{shown[:_SHOWN_CHARS]}..."


class ArmfleetError(Exception):
    """Root of every error armfleet raises for something a user can fix."""


class UnknownModel(ArmfleetError):
    def __init__(self, name: str, available: Sequence[str]) -> None:
        self.name = name
        self.available = tuple(available)
        super().__init__(f"model {shown_name(name)} not found; available: {_choices(available)}")


class InvalidArmName(ArmfleetError):
    """An arm name that breaks the naming rule of :mod:`armfleet.checks.names`.

    Attributes:
        name: what was given.
        problem: what is wrong with it and what is valid.
    """

    def __init__(self, name: object, problem: str) -> None:
        self.name, self.problem = name, problem
        super().__init__(f"arm name {shown_name(name)} {problem}")


class DuplicateArmName(ArmfleetError):
    def __init__(self, name: str, existing: Sequence[str]) -> None:
        self.name = name
        super().__init__(
            f"arm name {shown_name(name)} is already used in this world; arms: {_choices(existing)}"
        )


class UnknownArm(ArmfleetError):
    def __init__(self, name: str, existing: Sequence[str]) -> None:
        self.name = name
        super().__init__(f"no arm named {shown_name(name)}; arms: {_choices(existing)}")


class UnknownFrame(ArmfleetError):
    def __init__(self, frame: str, hint: str) -> None:
        self.frame = frame
        super().__init__(f"frame {shown_name(frame)} not found; {hint}")


class TargetLengthError(ArmfleetError):
    def __init__(self, arm: str, got: int, joint_names: Sequence[str]) -> None:
        self.arm = arm
        super().__init__(
            f"{arm}: got {got} target positions, expected {len(joint_names)} "
            f"(one per joint: {', '.join(joint_names)})"
        )


class TargetTypeError(ArmfleetError):
    def __init__(self, arm: str, joint_names: Sequence[str]) -> None:
        self.arm = arm
        super().__init__(f"{arm}: targets must be numbers, one per joint: {', '.join(joint_names)}")


class NonFiniteTarget(ArmfleetError):
    def __init__(self, arm: str, joint: str, value: float) -> None:
        self.arm, self.joint = arm, joint
        super().__init__(f"{arm}: target for {joint} is {value}; targets must be finite numbers")


class JointLimitError(ArmfleetError):
    def __init__(self, arm: str, joint: str, value: float, lower: float, upper: float) -> None:
        self.arm, self.joint = arm, joint
        self.value, self.lower, self.upper = value, lower, upper
        super().__init__(
            f"{arm}: target {value:.6g} for {joint} is outside its limits "
            f"[{lower:.6g}, {upper:.6g}]"
        )


class MotionLimitError(ArmfleetError):
    def __init__(self, arm: str, joint: str, value: float, lower: float, upper: float) -> None:
        self.arm, self.joint = arm, joint
        super().__init__(
            f"{arm}: from its current motion the arm cannot reach this target without taking "
            f"{joint} to {value:.6g}, outside its limits [{lower:.6g}, {upper:.6g}]; "
            "wait for the motion to slow down or choose another target"
        )


class SelfContactError(MotionLimitError):
    """A motion that would drive an arm into itself, refused before anything moved
    (see :mod:`armfleet.arms.self_contact`). A motion limit, as a joint limit on the way is.

    Attributes:
        arm: the arm's name.
        link, other_link: the two links of the arm that would touch.
        distance_m: their signed distance [m] where they come closest to touching;
            negative: overlap.
        clearance_m: the gap required between two links of one arm [m] (as at spawn).
        at_target: whether they touch at the target itself (else on the way to it).
    """

    def __init__(
        self, arm: str, link: str, other_link: str, distance_m: float, clearance_m: float,
        at_target: bool,
    ) -> None:  # fmt: skip
        self.arm, self.link, self.other_link = arm, link, other_link
        self.distance_m, self.clearance_m, self.at_target = distance_m, clearance_m, at_target
        if not at_target:  # where the motion first comes too close: the first contact
            ArmfleetError.__init__(
                self,
                f"{arm} would touch itself on the way to this target ({link} / {other_link} "
                f"come within {clearance_m * 1e3:g} mm of each other); nothing moved: choose "
                "another target, or go around with avoid_collisions=True (CLI: "
                "--avoid-collisions)",
            )
            return
        gap = (
            f"{-distance_m * 1e3:.1f} mm into each other"
            if distance_m < 0
            else f"{distance_m * 1e3:.2f} mm apart, closer than {clearance_m * 1e3:g} mm"
        )
        ArmfleetError.__init__(
            self,
            f"{arm} would touch itself at this target ({link} / {other_link}, {gap}); "
            "nothing moved: choose a target clear of itself",
        )


class ProtectiveStopError(ArmfleetError):
    def __init__(self, arm: str, reason: str) -> None:
        self.arm, self.reason = arm, reason
        super().__init__(
            f"{arm} is in protective stop ({reason}); call reset_stop() "
            f"(CLI: armfleet reset {arm}) before moving it"
        )


class ArmFault(ArmfleetError):
    def __init__(self, arm: str, reason: str) -> None:
        self.arm, self.reason = arm, reason
        super().__init__(
            f"{arm} is in error ({reason}); call reset() (CLI: armfleet reset {arm}) "
            "before moving it"
        )


class PoseError(ArmfleetError):
    """A spawn pose that cannot be parsed or is not finite."""


class DescriptionError(ArmfleetError):
    """A robot description (xacro/URDF) that cannot be expanded or loaded."""


class ResourceNotFound(DescriptionError):
    def __init__(self, uri: str, searched: Sequence[str]) -> None:
        self.uri = uri
        self.searched = tuple(searched)
        super().__init__(
            f"cannot resolve {shown_name(uri)}; searched: {', '.join(searched) or '(nothing)'}"
        )


class ModelSettingError(DescriptionError):
    """A setting of a model file (``tool_link``, ``home``, ...) that cannot be read.

    Attributes:
        source: where the settings came from (a settings file, ``spawn``, a spec field).
        key: the setting, e.g. ``home`` or ``end_effector.at_link``.
        problem: what is wrong and what is valid.
    """

    def __init__(self, source: str, key: str, problem: str) -> None:
        self.source, self.key, self.problem = source, key, problem
        super().__init__(f"{source}: {key}: {problem}")


class ParameterError(ArmfleetError):
    """A controller parameter file or override that does not fit its schema."""


class BringupError(ArmfleetError):
    """An arm that did not reach a bring-up stage in time."""


class WorldClosed(ArmfleetError):
    def __init__(self) -> None:
        super().__init__("this world is closed; create a new armfleet.World()")


class WorldBusy(ArmfleetError):
    """A call that steps or changes the world, made where it would break a step:
    from another thread while one steps it, or from inside a step (a bus subscriber).

    Attributes:
        call: what was called (``"spawn"``).
        reason: why not now.
    """

    def __init__(self, call: str, reason: str) -> None:
        self.call = call
        self.reason = reason
        super().__init__(
            f"world.{call}() refused: {reason}; hand it to world.submit(...), which runs it "
            f"in the stepping thread at the next step boundary"
        )


class InvalidNumber(ArmfleetError):
    """An argument that must be a finite real number (or numbers), not text, bool,
    complex or None, and within its range.

    Attributes:
        argument: its name (``"dt"``, ``"bob: gripper width"``).
        value: what was given.
        valid: what would be right, with its unit.
    """

    def __init__(self, argument: str, value: object, valid: str) -> None:
        self.argument, self.value, self.valid = argument, value, valid
        shown = " ".join(repr(value).split())  # one line, even for an array
        if len(shown) > 60:
            shown = shown[:57] + "..."
        super().__init__(f"{argument} = {shown} is invalid; give {valid}")


class InvalidFlag(ArmfleetError):
    """A yes/no argument that is not a bool (``linear='no'`` would read as yes).

    Attributes:
        argument: its name (``"linear"``, ``"viewer"``).
        value: what was given.
    """

    def __init__(self, argument: str, value: object) -> None:
        self.argument, self.value = argument, value
        shown = " ".join(repr(value).split())
        if len(shown) > 60:
            shown = shown[:57] + "..."
        super().__init__(f"{argument} = {shown} is invalid; give True or False")


class ObjectError(ArmfleetError):
    """A scene object that cannot be made as asked (shape, size, mass, mesh file, name...).

    Attributes:
        name: the object's name.
        field: the offending argument (``"shape"``, ``"size"``, ``"mass"``, ...).
        problem: what is wrong and what would be right.
    """

    def __init__(self, name: object, field: str, problem: str) -> None:
        self.name, self.field, self.problem = name, field, problem
        super().__init__(f"object {shown_name(name)}: {field}: {problem}")


class UnknownObject(ArmfleetError):
    def __init__(self, name: str, existing: Sequence[str]) -> None:
        self.name = name
        super().__init__(f"no object named {shown_name(name)}; objects: {_choices(existing)}")


class NameInUse(ArmfleetError):
    """A new arm or object named like something already in the world."""

    def __init__(self, name: str, kind: str, arms: Sequence[str], objects: Sequence[str]) -> None:
        self.name = name
        super().__init__(
            f"name {shown_name(name)} is already used in this world by {kind}; names are unique "
            f"across arms ({_choices(arms)}) and objects ({_choices(objects)})"
        )


class FrameInUse(ArmfleetError):
    """A new arm or object with a frame another arm or object owns already.

    Attributes:
        frame: the frame both would own.
        claimant: the newcomer, e.g. ``"arm x_panda"``.
        owner: who owns the frame, e.g. ``"arm x"``.
    """

    def __init__(self, frame: str, claimant: str, owner: str) -> None:
        self.frame, self.claimant, self.owner = frame, claimant, owner
        super().__init__(
            f"{claimant} would own frame {frame!r}, which is {owner}'s already; every frame "
            f"has one owner: give the {claimant.split()[0]} another name"
        )


class StartPoseCollision(ArmfleetError):
    """An arm that would touch something the moment it enters the world.

    Attributes:
        arm: the arm's name.
        link: its link that would touch.
        other: what it would touch: an arm, an object, ``"ground"``, or ``arm`` itself.
        other_link: the link of ``other`` (``""`` for an object or the ground).
        distance_m: signed distance between the two [m]; negative: overlap.
        clearance_m: the clearance required [m].
    """

    def __init__(
        self, arm: str, link: str, other: str, other_link: str, distance_m: float,
        clearance_m: float,
    ) -> None:  # fmt: skip
        self.arm, self.link, self.other, self.other_link = arm, link, other, other_link
        self.distance_m, self.clearance_m = distance_m, clearance_m
        what = "itself" if other == arm else other
        gap = (
            f"{-distance_m * 1e3:.1f} mm into it"
            if distance_m < 0
            else f"{distance_m * 1e3:.2f} mm from it, closer than {clearance_m * 1e3:g} mm"
        )
        super().__init__(
            f"{arm} would touch {what} at its start pose ({link} / {other_link or other}, "
            f"{gap}); nothing was spawned: choose a base pose or initial positions clear of it"
        )


class ObjectCollision(ObjectError):
    """A scene object that would touch an arm, or overlap the floor or another object,
    where it is added (see :mod:`armfleet.objects.object_clearance`).

    Attributes:
        other: the arm, object or ``"ground"`` in the way.
        other_link: the arm's link (``""`` for an object or the ground).
        distance_m: signed distance between the two [m]; negative: overlap.
        allowed_m: the smallest distance allowed there [m] (an arm's clearance, or
            minus the overlap a resting object may have).
        outcome: what was left as it was (``"nothing was added"``, or for a
            teleport ``"it was not moved"``).
    """

    def __init__(
        self,
        name: str,
        other: str,
        other_link: str,
        distance_m: float,
        allowed_m: float,
        outcome: str = "nothing was added",
    ) -> None:
        self.other, self.other_link = other, other_link
        self.distance_m, self.allowed_m = distance_m, allowed_m
        if allowed_m > 0:  # an arm
            verb, rule = "touch", f"keep {allowed_m * 1e3:g} mm clear of an arm"
        else:
            verb, rule = "overlap", f"a resting object may sink {-allowed_m * 1e3:g} mm at most"
        gap = f"{-distance_m * 1e3:.1f} mm into it" if distance_m < 0 else (
            f"{distance_m * 1e3:.2f} mm from it"
        )  # fmt: skip
        where = f"{other_link}, " if other_link else ""
        super().__init__(
            name,
            "at",
            f"it would {verb} {other} there ({where}{gap}; {rule}); {outcome}: "
            "choose a pose clear of it",
        )


class NoGripper(ArmfleetError):
    """The arm's model has no fingers to grip with."""

    def __init__(self, arm: str, model: str) -> None:
        self.arm, self.model = arm, model
        super().__init__(
            f"{arm} ({model}) has no gripper: only models with prismatic fingers have one "
            "(e.g. panda)"
        )


class GripperCommandError(ArmfleetError):
    """A gripper width or force outside what the fingers can do."""

    def __init__(
        self, arm: str, field: str, value: float, unit: str, low: float, high: float
    ) -> None:
        self.arm, self.field, self.value = arm, field, value
        opening = "(" if field == "force" else "["
        super().__init__(
            f"{arm}: gripper {field} {value:g} {unit} is invalid; give a value in "
            f"{opening}{low:g}, {high:g}] {unit}"
        )


class TargetPoseError(ArmfleetError):
    """A Cartesian goal that is not a rigid transform (4x4 homogeneous matrix or SE3)."""


class UnreachablePose(ArmfleetError):
    """No joint positions within the limits put the arm's frame at the wanted pose."""

    def __init__(
        self,
        arm: str,
        link: str,
        position_error_m: float,
        rotation_error_rad: float,
        where: str = "",
    ) -> None:
        self.arm, self.link = arm, link
        self.position_error_m, self.rotation_error_rad = position_error_m, rotation_error_rad
        super().__init__(
            f"{arm}: {link} cannot reach the pose{where} within the joint limits (best residual "
            f"{position_error_m * 1e3:.1f} mm, {rotation_error_rad * 1e3:.1f} mrad); nothing "
            "moved: choose a pose within the arm's reach"
        )


class ArmInMotion(ArmfleetError):
    """A motion that must start from rest was asked of a moving arm."""

    def __init__(self, arm: str, what: str) -> None:
        self.arm = arm
        super().__init__(
            f"{arm} is moving; {what} starts from rest: wait until arm.is_moving is False "
            "(the current motion goes on)"
        )


class MissingExtra(ArmfleetError):
    """An optional feature whose extra (its optional dependencies) is not installed."""

    def __init__(self, feature: str, extra: str, missing: str) -> None:
        self.feature, self.extra, self.missing = feature, extra, missing
        super().__init__(
            f"{feature} needs armfleet's '{extra}' extra ({missing} is not installed): "
            f"pip install 'armfleet[{extra}]' (from a clone: pip install '.[{extra}]')"
        )


class PackageNotFound(DescriptionError):
    """A ROS package a description names (``package://``, ``$(find)``) found nowhere."""

    def __init__(self, package: str, searched: Sequence[str]) -> None:
        self.package = package
        self.searched = tuple(searched)
        super().__init__(
            f"package {shown_name(package)} not found; searched: "
            f"{', '.join(searched) or '(nothing)'}; add its folder with --package-path DIR "
            "(or ARMFLEET_PACKAGE_PATH)"
        )
