"""The Foxglove services that command the arms: ``/move``, ``/move_together``, ``/grip``,
``/reset``.

Each is the live API's service of the same name (:mod:`armfleet.services.world_services`):
the request, a JSON object, goes through the same checks
(:class:`~armfleet.services.arguments.Arguments` with the live API's fields, then
``prepare_*`` in the Foxglove server's thread), and the work it returns runs in the
stepping thread through ``world.submit``; the handler waits for its result at most
:data:`CALL_TIMEOUT_S`. A refused request raises, and the Foxglove server sends the
client a ``serviceCallFailure`` naming the problem; the world never sees it.

Request and response are JSON under JSON Schemas (:data:`SERVICE_SCHEMAS`), so
Foxglove's Service Call panel shows what to send.
"""

from __future__ import annotations

import json
import logging
import math
import queue
from collections.abc import Callable
from concurrent.futures import CancelledError
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import foxglove

from armfleet.errors import ArmfleetError
from armfleet.foxglove.channels import JSON, sdk_schema
from armfleet.foxglove.errors import ServiceCallError
from armfleet.recording.schemas import MessageSchema, Schema, number, numbers, obj, strings
from armfleet.services.arguments import Arguments
from armfleet.services.planning_options import PlanningOptions
from armfleet.services.protocol import Service
from armfleet.services.world_services import FIELDS, WorldServices

if TYPE_CHECKING:
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: Longest wait for the stepping thread to run a call [s] (plus a plan's budget).
CALL_TIMEOUT_S = 10.0
#: Largest request accepted [bytes].
MAX_REQUEST_BYTES = 64 * 1024
#: Package of the service types.
SERVICE_PACKAGE = "armfleet_srvs/srv/"

_PLANNING: dict[str, Schema] = {
    "avoid_collisions": {
        "type": "boolean",
        "description": "plan around obstacles and other arms (default false: a straight line)",
    },
    "clearance_m": number("margin kept from other bodies [m], with avoid_collisions"),
    "timeout_s": number("planning budget [s], with avoid_collisions"),
    "budget": number("planner iterations instead of timeout_s (reproducible), with planning"),
}
_TIMED = {
    "time_s": number("simulated time of the call [s]"),
    "duration_s": number("duration of the motion [s]"),
}


def _request(name: str, properties: dict[str, Schema], optional: tuple[str, ...]) -> MessageSchema:
    schema = obj(properties, title=f"{SERVICE_PACKAGE}{name}_Request", optional=optional)
    return MessageSchema(schema["title"], {**schema, "additionalProperties": False})


def _response(name: str, properties: dict[str, Schema]) -> MessageSchema:
    schema = obj(properties, title=f"{SERVICE_PACKAGE}{name}_Response", optional=tuple(properties))
    return MessageSchema(schema["title"], schema)


@dataclass(frozen=True)
class ServiceSpec:
    """One Foxglove service: its name, its live API counterpart and its schemas.

    Attributes:
        name: the Foxglove service name (``/move``).
        service: the live API service whose fields and checks it uses.
        type_name: the service type shown by Foxglove (``armfleet_srvs/srv/Move``).
        request: JSON Schema of the request.
        response: JSON Schema of the response.
        example: a request, for the documentation and the tests.
    """

    name: str
    service: Service
    type_name: str
    request: MessageSchema
    response: MessageSchema
    example: dict[str, Any]


_HOME = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]

#: The services, in the order they are advertised.
SERVICE_SCHEMAS: tuple[ServiceSpec, ...] = (
    ServiceSpec(
        "/move",
        Service.MOVE,
        SERVICE_PACKAGE + "Move",
        _request(
            "Move",
            {
                "name": {"type": "string", "description": "arm name, e.g. bob"},
                "positions": numbers("target of every joint, in /<arm>/joint_states order"),
                **_PLANNING,
            },
            optional=tuple(_PLANNING),
        ),
        _response("Move", {**_TIMED, "moving": {"type": "boolean"}}),
        {"name": "bob", "positions": [0.3, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8]},
    ),
    ServiceSpec(
        "/move_together",
        Service.MOVE_TOGETHER,
        SERVICE_PACKAGE + "MoveTogether",
        _request(
            "MoveTogether",
            {
                "targets": {
                    "type": "object",
                    "description": "per arm name, its joint target; the arms arrive together",
                    "additionalProperties": {"type": "array", "items": {"type": "number"}},
                },
                **_PLANNING,
            },
            optional=tuple(_PLANNING),
        ),
        _response("MoveTogether", {**_TIMED, "arms": strings("the arms moved")}),
        {"targets": {"bob": _HOME, "toby": [0.3, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8]}},
    ),
    ServiceSpec(
        "/grip",
        Service.GRIP,
        SERVICE_PACKAGE + "Grip",
        _request(
            "Grip",
            {
                "name": {"type": "string", "description": "arm name"},
                "action": {"type": "string", "enum": ["open", "close", "width"]},
                "width": number("opening [m; rad for revolute jaws], with action 'width'"),
                "force": number("grip force per finger [N; N m for revolute jaws]"),
            },
            optional=("width", "force"),
        ),
        _response(
            "Grip",
            {
                "width": number("[m]"),
                "target_width": number("[m]"),
                "force": number("[N]"),
                "mode": {"type": "string"},
                "holding": {"type": "boolean"},
                "max_width": number("[m; rad for revolute jaws]"),
                "max_force": number("[N; N m for revolute jaws]"),
                "min_width": number("[m; rad for revolute jaws]"),
                "width_unit": {"type": "string", "enum": ["m", "rad"]},
                "force_unit": {"type": "string", "enum": ["N", "N m"]},
            },
        ),
        {"name": "bob", "action": "close", "force": 20.0},
    ),
    ServiceSpec(
        "/reset",
        Service.RESET,
        SERVICE_PACKAGE + "Reset",
        _request(
            "Reset",
            {
                "name": {"type": "string", "description": "arm name"},
                "stop_only": {
                    "type": "boolean",
                    "description": "clear a protective stop only, not a fault (default false)",
                },
            },
            optional=("stop_only",),
        ),
        _response(
            "Reset",
            {
                "name": {"type": "string"},
                "mode": {"type": "string"},
                "reason": {"type": "string"},
                "positions": numbers("[rad or m]"),
            },
        ),
        {"name": "bob"},
    ),
)


class ArmServices:
    """The Foxglove services of one world.

    Args:
        world: the world commanded; whoever steps it must keep stepping for calls to
            be answered (a call waits at most :data:`CALL_TIMEOUT_S`).
        address: the server's address (as the live API reports its own).
    """

    def __init__(self, world: World, address: str) -> None:
        self._world = world
        live = WorldServices(world, None, address)
        self._prepare: dict[Service, Callable[[Arguments], Callable[[], Any]]] = {
            spec.service: _prepare_of(live, spec.service) for spec in SERVICE_SCHEMAS
        }

    def sdk_services(self) -> list[foxglove.Service]:
        """The services as the Foxglove SDK takes them."""
        return [
            foxglove.Service(
                spec.name,
                schema=foxglove.ServiceSchema(
                    spec.type_name,
                    request=foxglove.MessageSchema(encoding=JSON, schema=sdk_schema(spec.request)),
                    response=foxglove.MessageSchema(
                        encoding=JSON, schema=sdk_schema(spec.response)
                    ),
                ),
                handler=self._handler(spec),
            )
            for spec in SERVICE_SCHEMAS
        ]

    def _handler(self, spec: ServiceSpec) -> Callable[[foxglove.ServiceRequest], bytes]:
        def handle(request: foxglove.ServiceRequest) -> bytes:
            try:
                return self.call(spec, request.encoding, request.payload)
            except ArmfleetError as exc:
                logger.info("foxglove: refused a call of %s: %s", spec.name, exc)
                raise
            except Exception:
                logger.exception("foxglove: a call of %s failed", spec.name)
                raise

        return handle

    def call(self, spec: ServiceSpec, encoding: str, payload: bytes) -> bytes:
        """Check a request, run it in the stepping thread, and return the JSON response.

        Raises:
            ServiceCallError: not JSON, too large, or the world did not answer in time.
            ArmfleetError: the live API's checks or the world's refused it.
        """
        if encoding != JSON:
            raise ServiceCallError(spec.name, f"encoding {encoding!r} is not supported; use json")
        raw = _parse(spec.name, payload)
        args = Arguments(spec.name, raw, FIELDS[spec.service], label="the request")
        work = self._prepare[spec.service](args)
        try:
            future = self._world.submit(work)
        except queue.Full:
            raise ServiceCallError(spec.name, "the world has too many calls waiting") from None
        timeout = CALL_TIMEOUT_S
        if args.raw("avoid_collisions") is True:
            timeout += PlanningOptions.from_request(spec.name, args).work_s + 5.0
        try:
            result = future.result(timeout=timeout)
        except FutureTimeout:
            future.cancel()
            raise ServiceCallError(
                spec.name,
                f"the world did not run the call within {timeout:g} s (is it stepping, "
                "or paused?); nothing was done",
            ) from None
        except CancelledError:
            raise ServiceCallError(spec.name, "the call was cancelled") from None
        return json.dumps(_finite(result), separators=(",", ":"), allow_nan=False).encode()


def _prepare_of(live: WorldServices, service: Service) -> Callable[[Arguments], Callable[[], Any]]:
    """The live API's ``prepare`` of ``service``."""

    def prepare(args: Arguments) -> Callable[[], Any]:
        work = live.prepare(service, args)
        assert work is not None  # the four services are plain ones
        return work

    return prepare


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number; give finite numbers")


def _parse(service: str, payload: bytes) -> Any:
    if len(payload) > MAX_REQUEST_BYTES:
        raise ServiceCallError(
            service, f"the request is {len(payload)} bytes; the limit is {MAX_REQUEST_BYTES}"
        )
    try:
        return json.loads(payload.decode("utf-8"), parse_constant=_reject_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise ServiceCallError(service, f"the request is not valid JSON ({exc})") from None


def _finite(value: Any) -> Any:
    """``value`` with non-finite numbers as None (JSON has no NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(key): _finite(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(item) for item in value]
    return value
