"""The capacity policy of a shared world: what one client, and all clients together, may add.

Every arm costs the world's stepping thread its share of each step, for everyone: one
client spawned 120 Pandas into a shared world, its real-time factor fell to 0.014 and
another client's 0.7 s motion took 48.5 s. So the world's owner sets quotas, and the
live API refuses, in one line naming the quota and how its owner raises it, a request
past them, with nothing applied:

- per client (one connection: a :class:`~armfleet.remote.Client`, one CLI command):
  the arms and objects it added that are still in the world, and its requests in flight;
- for the world (all clients together, so a client cannot get round its quota by
  connecting again): the arms and objects in the world, whoever added them, past which
  a client adds none (the owner's own program is not bound by them).

An arm or object counts toward the client that added it while it is in the world; when
that client disconnects, what it added stays in the world (and counts toward the world's
totals), no longer toward anyone. Counted in the stepping thread, right before the work,
so two requests cannot both take the last place.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Collection
from dataclasses import dataclass, fields
from typing import Any

from armfleet.checks.number_ranges import NumberRange
from armfleet.errors import ArmfleetError
from armfleet.services.protocol import MAX_IN_FLIGHT_PER_CLIENT, MAX_PENDING_REQUESTS

#: Valid arm and object counts of a quota (0: clients may add none).
QUOTA_COUNT = NumberRange(0, 10_000, "a count", integer=True)
#: Valid requests in flight per client (at least one, at most what a world keeps).
QUOTA_REQUESTS = NumberRange(1, MAX_PENDING_REQUESTS, "requests", integer=True)

#: Defaults. Measured on the 2-core development machine (load 3.5), one 1 ms step of a
#: world of Pandas takes 0.26 ms with 1, 1.0 ms with 8 and 2.2 ms with 16: one client
#: alone stays about real time, and the whole world at no worse than half of it.
DEFAULT_ARMS_PER_CLIENT = 8
DEFAULT_OBJECTS_PER_CLIENT = 64
DEFAULT_WORLD_ARMS = 16
DEFAULT_WORLD_OBJECTS = 256


@dataclass(frozen=True)
class ClientQuotas:
    """What the clients of a served world may add; set by the world's owner.

    Attributes:
        arms_per_client: arms one client may have in the world at once.
        objects_per_client: objects one client may have in the world at once.
        requests_per_client: requests one client may have in flight (waits and replies it
            has not read included).
        world_arms: arms in the world (whoever spawned them) past which clients spawn none.
        world_objects: objects in the world past which clients add none.

    Raises:
        InvalidNumber: a quota is not an integer in its range.
    """

    arms_per_client: int = DEFAULT_ARMS_PER_CLIENT
    objects_per_client: int = DEFAULT_OBJECTS_PER_CLIENT
    requests_per_client: int = MAX_IN_FLIGHT_PER_CLIENT
    world_arms: int = DEFAULT_WORLD_ARMS
    world_objects: int = DEFAULT_WORLD_OBJECTS

    def __post_init__(self) -> None:
        for field in fields(self):
            valid = QUOTA_REQUESTS if field.name == "requests_per_client" else QUOTA_COUNT
            value = getattr(self, field.name)
            valid.check(value, field.name)
            object.__setattr__(self, field.name, int(value))


#: How the owner raises each quota: the option of ``armfleet spawn``/``launch``, and the
#: field of :class:`ClientQuotas` (``armfleet.remote.serve(world, quotas=...)``).
RAISED_BY = {field.name: f"--max-{field.name.replace('_', '-')}" for field in fields(ClientQuotas)}


def how_to_raise(quota: str) -> str:
    """E.g. ``the world's owner sets it: armfleet spawn/launch --max-arms-per-client N, or
    serve(world, quotas=ClientQuotas(arms_per_client=N))``."""
    return (
        f"the world's owner sets it: armfleet spawn/launch {RAISED_BY[quota]} N, or "
        f"serve(world, quotas=ClientQuotas({quota}=N))"
    )


class QuotaExceeded(ArmfleetError):
    """A request past one of the world's quotas; nothing was applied.

    Attributes:
        quota: the :class:`ClientQuotas` field (``arms_per_client``, ``world_arms``...).
        limit: its value.
    """

    def __init__(self, service: str, quota: str, limit: int, held: str, remedy: str) -> None:
        self.quota, self.limit = quota, limit
        super().__init__(
            f"{service}: {held}, the {quota.replace('_', ' ')} quota ({limit}); {remedy} "
            f"(nothing was applied; {how_to_raise(quota)})"
        )


class QuotaLedger:
    """Who added which arm and object, checked against :class:`ClientQuotas`.

    Thread-safe: checks and records run in the stepping thread, :meth:`forget` in the
    server thread.
    """

    def __init__(self, quotas: ClientQuotas) -> None:
        self.quotas = quotas
        self._owners: dict[str, dict[str, bytes]] = {"arms": {}, "objects": {}}
        self._lock = threading.Lock()

    def spawning(
        self, peer: bytes, name: str, arms: Callable[[], Collection[str]], work: Callable[[], Any]
    ) -> Callable[[], Any]:
        """``work`` (a spawn of arm ``name`` for ``peer``), run only within the quotas.

        Args:
            arms: the world's arms now (called in the stepping thread).
        """
        quotas = self.quotas
        return self._limited(
            "spawn", "arms", peer, name, arms, work,
            (quotas.arms_per_client, "arms_per_client", "remove one of its arms first"),
            (quotas.world_arms, "world_arms", "remove an arm first"),
        )  # fmt: skip

    def adding_object(
        self,
        peer: bytes,
        name: str,
        objects: Callable[[], Collection[str]],
        work: Callable[[], Any],
    ) -> Callable[[], Any]:
        """``work`` (an ``add_object`` of ``name`` for ``peer``), run only within the quotas."""
        quotas = self.quotas
        return self._limited(
            "add_object", "objects", peer, name, objects, work,
            (quotas.objects_per_client, "objects_per_client", "remove one of its objects first"),
            (quotas.world_objects, "world_objects", "remove an object first"),
        )  # fmt: skip

    def _limited(
        self,
        service: str,
        kind: str,
        peer: bytes,
        name: str,
        present: Callable[[], Collection[str]],
        work: Callable[[], Any],
        per_client: tuple[int, str, str],
        world: tuple[int, str, str],
    ) -> Callable[[], Any]:
        owners = self._owners[kind]

        def limited() -> Any:
            now = present()
            with self._lock:
                for gone in [added for added in owners if added not in now]:
                    del owners[gone]
                mine = sum(1 for owner in owners.values() if owner == peer)
            limit, quota, remedy = per_client
            if mine >= limit:
                held = f"this client has {_count(mine, kind)} in the world"
                raise QuotaExceeded(service, quota, limit, held, remedy)
            limit, quota, remedy = world
            if len(now) >= limit:
                held = f"the world holds {_count(len(now), kind)}"
                raise QuotaExceeded(service, quota, limit, held, remedy)
            result = work()
            with self._lock:
                owners[name] = peer
            return result

        return limited

    def forget(self, peer: bytes) -> None:
        """``peer`` disconnected: what it added no longer counts toward it."""
        with self._lock:
            for owners in self._owners.values():
                for name in [name for name, owner in owners.items() if owner == peer]:
                    del owners[name]


def _count(number: int, kind: str) -> str:
    """``1 arm``, ``3 arms`` (``kind``: a plural ending in s)."""
    return f"{number} {kind if number != 1 else kind[:-1]}"
