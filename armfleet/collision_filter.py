"""Which contacts of an arm count: not between links of one rigid piece or one joint apart,
not between pairs its SRDF rules out, and not between the floor and links that never move."""

from __future__ import annotations

from collections.abc import Iterable

import pybullet as p

from armfleet.arm_body import ArmBody


def rigid_groups(body: ArmBody) -> dict[int, int]:
    """Link index -> index of the first link of its rigid piece (-1: the fixed base)."""
    groups: dict[int, int] = {-1: -1}
    for link in sorted(body.link_parents):
        parent, moves = body.link_parents[link]
        groups[link] = link if moves else groups[parent]
    return groups


def filter_collisions(
    client: int, body: ArmBody, ground: int, ignored_pairs: Iterable[tuple[str, str]]
) -> None:
    """Switch off the contacts of ``body`` that say nothing about the arm's safety.

    - links of one rigid piece, or of two pieces one movable joint apart (adjacent);
    - pairs the upstream SRDF lists in ``<disable_collisions>``;
    - the floor against links that never move (the base stands on it).
    """
    groups = rigid_groups(body)
    parent_group = {
        group: groups[body.link_parents[group][0]] for group in set(groups.values()) if group >= 0
    }

    def adjacent(a: int, b: int) -> bool:
        ga, gb = groups[a], groups[b]
        return ga == gb or parent_group.get(ga) == gb or parent_group.get(gb) == ga

    # Links without a collision shape (landmarks, flanges) touch nothing: no filter
    # needed (each setCollisionFilterPair costs tens of µs in a full world).
    solid = [
        link
        for link in sorted(body.link_parents)
        if p.getCollisionShapeData(body.body_id, link, physicsClientId=client)
    ]
    pairs = {(a, b) for i, a in enumerate(solid) for b in solid[i + 1 :] if adjacent(a, b)}
    known = set(body.link_names)
    for first, second in ignored_pairs:
        if first in known and second in known:
            a, b = body.link_index(first), body.link_index(second)
            if a in solid and b in solid:
                pairs.add((a, b))
    for a, b in pairs:
        if body.link_parents[a][0] == b or body.link_parents[b][0] == a:
            continue  # a link and its parent: ArmBody's load flags leave them out already
        p.setCollisionFilterPair(body.body_id, body.body_id, a, b, 0, physicsClientId=client)
    for link in solid:
        if groups[link] == -1:
            p.setCollisionFilterPair(ground, body.body_id, -1, link, 0, physicsClientId=client)
