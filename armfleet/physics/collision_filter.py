"""Which contacts of an arm count: not between links of one rigid piece or one joint apart,
not between pairs never seen touching in sampled configurations, and not between the floor
and links that never move."""

from __future__ import annotations

from collections.abc import Iterable

import pybullet as p

from armfleet.physics.arm_body import ArmBody


def rigid_groups(body: ArmBody) -> dict[int, int]:
    """Link index -> index of the first link of its rigid piece (-1: the fixed base)."""
    groups: dict[int, int] = {-1: -1}
    for link in sorted(body.link_parents):
        parent, moves = body.link_parents[link]
        groups[link] = link if moves else groups[parent]
    return groups


def solid_links(client: int, body: ArmBody) -> list[int]:
    """Link indices of ``body`` that have a collision shape (the others touch nothing),
    the base (-1) included."""
    return [
        link
        for link in [-1, *sorted(body.link_parents)]
        if p.getCollisionShapeData(body.body_id, link, physicsClientId=client)
    ]


def fixed_links(body: ArmBody) -> set[int]:
    """Links of ``body`` that never move (the base's rigid piece, -1 included)."""
    return {link for link, group in rigid_groups(body).items() if group == -1}


def ignored_self_pairs(
    client: int, body: ArmBody, ignored_pairs: Iterable[tuple[str, str]]
) -> set[tuple[int, int]]:
    """Pairs ``(a, b)``, ``a < b``, of solid links of ``body`` whose contacts don't count.

    - links of one rigid piece, or of two pieces one movable joint apart (adjacent);
    - ``ignored_pairs``: the description's pairs never seen touching
      (:mod:`armfleet.physics.contact_pairs`).
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
    solid = solid_links(client, body)
    pairs = {(a, b) for i, a in enumerate(solid) for b in solid[i + 1 :] if adjacent(a, b)}
    known = set(body.link_names)
    for first, second in ignored_pairs:
        if first in known and second in known:
            a, b = body.link_index(first), body.link_index(second)
            if a in solid and b in solid:
                pairs.add((min(a, b), max(a, b)))
    return pairs


def filter_collisions(
    client: int, body: ArmBody, ground: int, ignored_pairs: Iterable[tuple[str, str]]
) -> None:
    """Switch off the contacts of ``body`` that say nothing about the arm's safety:
    the :func:`ignored_self_pairs`, and the floor against the :func:`fixed_links`
    (the base stands on it)."""
    for a, b in ignored_self_pairs(client, body, ignored_pairs):
        if body.link_parents[b][0] == a:  # a < b: only b can be a's child
            continue  # a link and its parent: ArmBody's load flags leave them out already
        p.setCollisionFilterPair(body.body_id, body.body_id, a, b, 0, physicsClientId=client)
    fixed = fixed_links(body)
    for link in solid_links(client, body):
        if link in fixed:
            p.setCollisionFilterPair(ground, body.body_id, -1, link, 0, physicsClientId=client)
