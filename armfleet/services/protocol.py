"""The wire protocol of the live world API: frames, limits and service names.

One ZeroMQ ROUTER socket per world. A client talks to it through two DEALER
sockets: one for requests (one frame each, one reply each), one for streams
(topic messages pushed by the server). Every frame is one msgpack map:

- request:  ``{"id": int, "op": str, "args": {...}, "timeout_s": float}``
- reply:    ``{"kind": "reply", "id": int | None, "ok": true, "result": ...}``
  or ``{"kind": "reply", "id": ..., "ok": false, "error": {"type": str, "message": str}}``
  (a ``PlanningFailed`` error also has ``"fields"``: its reason, arms, links, samples and
  blocking arm, from which the client raises it again; see :mod:`armfleet.services.errors`)
- stream:   ``{"kind": "messages", "items": [[sub, dropped, type, message], ...]}``,
  ``{"kind": "tick"}`` (every second, so both ends notice the other going away),
  ``{"kind": "ended", "sub": int, "reason": str}`` (the topic went away: no more messages),
  ``{"kind": "closing", "reason": str}``.

Numbers are msgpack floats/ints, vectors are lists of floats: never pickle, never eval.
"""

from __future__ import annotations

import enum

from armfleet._version import __version__
from armfleet.checks.number_ranges import REQUEST_TIMEOUT_S

#: Bumped on any incompatible change; ``hello`` refuses a client speaking another one.
#: 2: a stream answers only to its socket and the request connection it attached for.
PROTOCOL_VERSION = 2
#: Largest request the server reads; a larger one gets an error reply [bytes].
MAX_REQUEST_BYTES = 256 * 1024
#: Larger frames are cut off by ZeroMQ itself, which drops that connection [bytes].
HARD_FRAME_LIMIT_BYTES = 16 * 1024 * 1024
#: Most messages the server packs into one stream frame.
MAX_BATCH = 256
#: Period of the server's ``tick`` frames on every stream [s].
TICK_PERIOD_S = 1.0
#: A stream with no frame for this long has lost its world [s].
STREAM_SILENCE_S = 4.0
#: Messages a subscription holds for a slow client before dropping the oldest.
DEFAULT_QUEUE_SIZE = 100
MAX_QUEUE_SIZE = 10_000
#: Subscriptions one stream may hold.
MAX_SUBSCRIPTIONS_PER_STREAM = 256
#: Streams one server serves at once.
MAX_STREAMS = 256
#: Requests one client may have in flight at once (waits and unread replies included);
#: more are refused, each with a reply, and the other clients are served meanwhile.
MAX_IN_FLIGHT_PER_CLIENT = 64
#: Requests one server keeps in flight at once, all clients together (waits included):
#: what the world's request queue holds, with room for the server's own work.
MAX_PENDING_REQUESTS = 768
#: Replies held for one client that sends faster than it reads; past it they are
#: dropped and the client told how many [bytes].
MAX_HELD_REPLY_BYTES = 4 * 1024 * 1024
#: Longest time a request may wait in the world's queue, whatever the client asks [s].
MAX_REQUEST_TIMEOUT_S = REQUEST_TIMEOUT_S.high


class Service(enum.Enum):
    """Requests a world answers (the ``op`` of a request)."""

    HELLO = "hello"
    ATTACH = "attach"
    INFO = "info"
    ARMS = "arms"
    ARM = "arm"
    JOINT_STATE = "joint_state"
    LOOKUP = "lookup"
    SPAWN = "spawn"
    REMOVE = "remove"
    MOVE = "move"
    MOVE_POSE = "move_pose"
    MOVE_TOGETHER = "move_together"
    GRIP = "grip"
    WAIT = "wait"
    RESET = "reset"
    TOPICS = "topics"
    SUBSCRIBE = "subscribe"
    UNSUBSCRIBE = "unsubscribe"
    PUBLISH = "publish"
    OBJECTS = "objects"
    ADD_OBJECT = "add_object"
    REMOVE_OBJECT = "remove_object"
    PAUSE = "pause"
    RESUME = "resume"
    STEP = "step"
    DETACH = "detach"


class FrameKind(enum.Enum):
    """What a frame from the server carries."""

    REPLY = "reply"
    MESSAGES = "messages"
    TICK = "tick"
    ENDED = "ended"
    CLOSING = "closing"


def armfleet_version() -> str:
    """The armfleet version of this side."""
    return __version__
