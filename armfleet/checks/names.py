"""Names of arms and scene objects: one rule for both, wherever a name enters.

An arm's name is its namespace ``/<name>`` and the prefix ``<name>_`` of every
link and joint; an object's name is its frame. A name matches
:data:`ARM_NAME_PATTERN` and has at most :data:`MAX_NAME_LENGTH` characters.

The length limit is not cosmetic: PyBullet's URDF loader crashes the whole
process (segmentation fault) on link names of about 1,255 characters, and
fails with a 10 KB message from about 1,010. 64 characters leave room for the
longest link name any model appends to the prefix, and keep topic names,
frames and messages readable.
"""

from __future__ import annotations

import re
from collections.abc import Collection

from armfleet.errors import DuplicateArmName, InvalidArmName

ARM_NAME_PATTERN = r"^[a-z][a-z0-9_]*$"
#: Names no arm or object may take: the root frame, and the floor's body name on
#: ``/collisions`` (an arm called ``ground`` would take the floor's contacts as its own).
RESERVED_NAMES = ("ground", "world")
#: Longest name of an arm or object [characters].
MAX_NAME_LENGTH = 64
_ARM_NAME = re.compile(ARM_NAME_PATTERN)


def name_problem(name: object) -> str | None:
    """Why ``name`` cannot name an arm or an object, or None if it can.

    The one rule both :func:`check_arm_name` and
    :func:`armfleet.objects.object_spec.check_object_name` apply.
    """
    if not isinstance(name, str) or not _ARM_NAME.fullmatch(name):
        return (
            f"is malformed; a name must match {ARM_NAME_PATTERN} "
            "(lowercase letter first, then lowercase letters, digits or '_')"
        )
    if len(name) > MAX_NAME_LENGTH:
        return f"is too long ({len(name)} characters); a name has at most {MAX_NAME_LENGTH}"
    return None


def check_arm_name(name: object, existing: Collection[str] = ()) -> str:
    """Return ``name`` if it is a well-formed name not in ``existing``; raise otherwise.

    Raises:
        InvalidArmName: malformed, too long, or one of :data:`RESERVED_NAMES`.
        DuplicateArmName: already in ``existing``.
    """
    problem = name_problem(name)
    if problem is None and name in RESERVED_NAMES:
        problem = (
            f"is reserved; a name must match {ARM_NAME_PATTERN} and not be "
            f"{' or '.join(RESERVED_NAMES)}"
        )
    if problem is not None:
        raise InvalidArmName(name, problem)
    assert isinstance(name, str)  # name_problem checked it
    if name in existing:
        raise DuplicateArmName(name, sorted(existing))
    return name
