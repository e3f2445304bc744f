"""Which link pairs of an arm can touch each other, found by sampling its configurations.

This is what MoveIt's setup assistant does to write an SRDF's ``<disable_collisions>``:
put the arm in many random configurations within its joint limits and keep every
pair of links that was ever in contact. A pair never seen touching is left out of
the physics' self-collision (it costs solver time and can tell nothing) and of the
contact monitor and the planner, which use the same pairs.

The sampling is armfleet's own rather than the upstream SRDF's, because an SRDF can
be wrong in the unsafe direction: the Panda's disables ``link5``-``link7`` and
``link5``-``hand``, which touch in about 8 % of random configurations (a folded
wrist); with the SRDF such a self-contact raised no protective stop.

Sampling a Panda 20,000 times takes about 1.2 s on the development machine, so the
result is cached on disk per description (its lean URDF text, the bytes of its
collision meshes, the sampling settings and PyBullet's version), in
``$XDG_CACHE_HOME/armfleet/contact-pairs`` (``~/.cache`` by default). A pair that
touches in fewer than about 1 in 20,000 configurations may be missed.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet as p

from armfleet.physics.lean_urdf import LeanUrdf

#: Random configurations sampled per model.
SAMPLES = 20_000
#: Seed of the sampling (the same description always gives the same pairs).
SEED = 0
#: Version of the sampling procedure, part of the cache key.
PROCEDURE = 1

LinkPair = tuple[str, str]


def touching_pairs(lean: LeanUrdf, samples: int = SAMPLES) -> frozenset[LinkPair]:
    """Pairs ``(a, b)``, ``a < b``, of links of ``lean`` (unprefixed, or as named in it)
    that touch in at least one of ``samples`` random configurations; cached on disk."""
    key = _cache_key(lean, samples)
    cached = _read_cache(key)
    if cached is not None:
        return cached
    pairs = _sample(lean, samples)
    _write_cache(key, pairs)
    return pairs


def solid_link_pairs(urdf: str) -> frozenset[LinkPair]:
    """Every pair ``(a, b)``, ``a < b``, of links of ``urdf`` with a collision shape."""
    robot = ET.fromstring(urdf)
    solid = sorted(
        link.get("name", "") for link in robot.iter("link") if link.find("collision") is not None
    )
    return frozenset((a, b) for i, a in enumerate(solid) for b in solid[i + 1 :])


def _sample(lean: LeanUrdf, samples: int) -> frozenset[LinkPair]:
    """Sample in a private PyBullet world: every pair but a link and its parent collides."""
    client = p.connect(p.DIRECT)
    fd, path = tempfile.mkstemp(suffix=".urdf", prefix="armfleet-sampling-")
    try:
        with os.fdopen(fd, "w") as file:
            file.write(lean.text)
        body = p.loadURDF(
            path, useFixedBase=True, flags=p.URDF_USE_SELF_COLLISION, physicsClientId=client
        )
        names = {-1: lean.base_link}
        movable: list[tuple[int, float, float]] = []
        for index in range(p.getNumJoints(body, physicsClientId=client)):
            info = p.getJointInfo(body, index, physicsClientId=client)
            names[index] = info[12].decode()
            if info[2] != p.JOINT_FIXED:
                lower, upper = float(info[8]), float(info[9])
                if lower > upper:  # no limits (continuous): a full turn
                    lower, upper = -np.pi, np.pi
                movable.append((index, lower, upper))
        rng = np.random.default_rng(SEED)
        lows = np.array([m[1] for m in movable])
        highs = np.array([m[2] for m in movable])
        found: set[LinkPair] = set()
        for configuration in rng.uniform(lows, highs, size=(samples, len(movable))):
            for (index, _, _), value in zip(movable, configuration, strict=True):
                p.resetJointState(body, index, float(value), physicsClientId=client)
            p.performCollisionDetection(physicsClientId=client)
            for point in p.getContactPoints(body, body, physicsClientId=client):
                if point[8] <= 0.0:  # in contact, not only near
                    a, b = names[point[3]], names[point[4]]
                    found.add((min(a, b), max(a, b)))
        return frozenset(found)
    finally:
        os.unlink(path)
        p.disconnect(client)


def _cache_key(lean: LeanUrdf, samples: int) -> str:
    digest = hashlib.sha256()
    digest.update(f"{PROCEDURE} {samples} {SEED} {p.getAPIVersion()}\n".encode())
    digest.update(lean.text.encode())
    for mesh in ET.fromstring(lean.text).iter("mesh"):
        filename = Path(mesh.get("filename", "").removeprefix("file://"))
        if filename.is_file():
            digest.update(filename.read_bytes())
    return digest.hexdigest()


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "armfleet" / "contact-pairs"


def _read_cache(key: str) -> frozenset[LinkPair] | None:
    try:
        pairs = json.loads((_cache_dir() / f"{key}.json").read_text())["touching"]
        return frozenset((str(a), str(b)) for a, b in pairs)
    except (OSError, ValueError, KeyError, TypeError):
        return None  # absent or unreadable: sample again


def _write_cache(key: str, pairs: frozenset[LinkPair]) -> None:
    """Best effort: a read-only or full disk only costs the next process a new sampling."""
    folder = _cache_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, temporary = tempfile.mkstemp(dir=folder, suffix=".tmp")
        with os.fdopen(fd, "w") as file:
            json.dump({"touching": sorted(pairs)}, file)
        os.replace(temporary, folder / f"{key}.json")  # atomic: readers never see half
    except OSError:
        pass
