"""What armfleet reads from an upstream SRDF: link pairs whose collisions don't matter."""

from __future__ import annotations

import xml.etree.ElementTree as ET

from armfleet.errors import DescriptionError


def disabled_collision_pairs(
    srdf_text: str, prefix: str, source: str
) -> tuple[tuple[str, str], ...]:
    """Prefixed link pairs listed in ``<disable_collisions>`` (adjacent, never in contact...).

    Args:
        srdf_text: the SRDF.
        prefix: the arm's prefix, prepended to every link name.
        source: where the text came from, for error messages.
    """
    try:
        root = ET.fromstring(srdf_text)
    except ET.ParseError as exc:
        raise DescriptionError(f"SRDF {source} is not valid XML: {exc}") from exc
    pairs = []
    for element in root.iter("disable_collisions"):
        first, second = element.get("link1"), element.get("link2")
        if not first or not second:
            raise DescriptionError(f"SRDF {source}: <disable_collisions> without link1/link2")
        pairs.append((prefix + first, prefix + second))
    return tuple(pairs)
