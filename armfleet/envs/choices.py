"""An option given as one of an enum's values (``action_kind="tool_delta"``)."""

from __future__ import annotations

import enum
from typing import TypeVar

from armfleet.envs.errors import InvalidOption

E = TypeVar("E", bound=enum.Enum)


def choose(kind: type[E], value: object, option: str) -> E:
    """``value`` as a member of ``kind`` (the member itself or its value).

    Raises:
        InvalidOption: naming ``option`` and listing the valid values.
    """
    if isinstance(value, kind):
        return value
    for member in kind:
        if value == member.value:
            return member
    raise InvalidOption(option, value, [member.value for member in kind])
