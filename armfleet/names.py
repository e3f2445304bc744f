"""Arm names: ``^[a-z][a-z0-9_]*$``, unique per world; namespace ``/<name>``, prefix ``<name>_``."""

from __future__ import annotations

import re
from collections.abc import Collection

from armfleet.errors import DuplicateArmName, InvalidArmName

ARM_NAME_PATTERN = r"^[a-z][a-z0-9_]*$"
_ARM_NAME = re.compile(ARM_NAME_PATTERN)


def check_arm_name(name: object, existing: Collection[str] = ()) -> str:
    """Return ``name`` if it is a well-formed name not in ``existing``; raise otherwise."""
    if not isinstance(name, str) or not _ARM_NAME.fullmatch(name) or name == "world":
        raise InvalidArmName(name, ARM_NAME_PATTERN)
    if name in existing:
        raise DuplicateArmName(name, sorted(existing))
    return name
