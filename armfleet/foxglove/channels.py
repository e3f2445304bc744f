"""Bus topics as Foxglove channels, subscribed to on the bus only while a client listens.

Every advertised topic of the world gets a Foxglove channel with the recording's
schema and JSON encoding (:func:`armfleet.recording.encode.encoder_for`, the very
encoders the MCAP recording uses), plus ``/<arm>/robot_description`` per arm
(``std_msgs/msg/String``, the URDF with ``package://`` mesh URIs: see
:mod:`armfleet.foxglove.assets`), and ``/scene_objects``, the objects' shapes
(:mod:`armfleet.foxglove.scene_objects`). A channel costs the world nothing until a client
subscribes: the Foxglove server's listener then asks the stepping thread (through
``world.submit``) to subscribe to the bus topic, and to drop that subscription when the
last client leaves. So ``/tf`` and ``/<arm>/position_controller/state``, computed only
for listeners (:meth:`armfleet.runtime.bus.Bus.has_subscribers`), stay off until watched.

The streams published every step (``/tf``, each arm's joint states and controller
and gripper states: :data:`STREAMED_TYPES`) go out at a display rate, one instant of
simulated time per ``stream_period_s`` (every arm's ``/tf`` of that step together): the
bus subscription carries the period, so between two instants ``/tf`` and the
controllers' states are not even computed. Everything else (commands, status,
collisions, bring-up, planned motions) goes out as published.

Latched topics (``/tf_static``) and the robot descriptions are sent again to every
client that subscribes, whenever it comes (a client already subscribed receives them
once more: harmless for static transforms and descriptions). The latched topics are
also repeated every :data:`LATCHED_REPEAT_S` of wall time while someone listens: an app
subscribes to a topic once for all its panels, and a panel that mounts after that first
delivery (Lichtblick's Raw Messages of ``/tf_static``, empty in 3 runs of 4) gets them
within a second.

The clock: Lichtblick and Foxglove stamp a live message with the server's latest time
broadcast, not with its log time. The time is therefore sent before the messages of each
new instant (and every :data:`TIME_PERIOD_S` when nothing else goes out): with the clock
sent only every 0.1 s, ten joint states shared one stamp in the app.

Arms coming and going: a watch on ``/bringup`` opens the channels of new topics and
arms; a watch on each arm's ``/<arm>/status`` learns, through the bus's ``on_gone``,
when the arm is removed, and closes its channels (the client sees them unadvertised).
The same status messages (10 Hz per arm) open the channels of topics advertised since
(``/<arm>/status`` itself, any topic first published later) and carry the simulated time
to the server.
"""

from __future__ import annotations

import functools
import logging
import queue
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import foxglove

from armfleet import topics
from armfleet.errors import WorldClosed
from armfleet.foxglove.assets import AssetLibrary
from armfleet.foxglove.scene_objects import SceneObjects
from armfleet.messages import ControllerState, GripperState, JointState
from armfleet.recording.encode import MessageEncoder, StringEncoder, encoder_for, stamp_ns
from armfleet.recording.schemas import MessageSchema

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.runtime.bus import Subscription
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: Encoding of every message and service payload.
JSON = "json"
#: Simulated time between two time broadcasts to the clients [s].
TIME_PERIOD_S = 0.1
#: Wall time between two repeats of the latched topics (``/tf_static``) [s].
LATCHED_REPEAT_S = 1.0
#: Topics of these types, and ``/tf``, are sent at the display rate, not every step.
STREAMED_TYPES = (JointState, ControllerState, GripperState)


def sdk_schema(schema: MessageSchema) -> foxglove.Schema:
    """The Foxglove SDK's form of a recording schema: same name, same JSON Schema bytes."""
    return foxglove.Schema(name=schema.name, encoding="jsonschema", data=schema.data)


@dataclass(eq=False)
class _TopicChannel:
    topic: str
    channel: foxglove.Channel
    encode: MessageEncoder
    #: Sent at the display rate (a stream), or every message.
    streamed: bool
    subscription: Subscription | None = None


@dataclass(eq=False)
class _DescriptionChannel:
    arm: Arm
    channel: foxglove.Channel
    message: bytes
    #: The watch on ``/<arm>/status`` (removal, time).
    watch: Subscription | None = field(default=None, repr=False)


class TopicChannels:
    """The Foxglove channels of one world, in one SDK context.

    Everything but :meth:`on_subscribe` / :meth:`on_unsubscribe` runs in the thread
    that steps the world (or while nobody steps it); those two only hand work to it.

    Args:
        world: the world whose topics are served.
        context: the SDK context of the server (channels of other worlds stay apart).
        assets: the allowlist the arms' meshes are added to.
        on_time: called with the simulated time [ns] before the messages of each new
            instant, and about every :data:`TIME_PERIOD_S` when nothing is sent.
        stream_period_s: simulated time between two instants of the streamed topics
            [s]; None: every step.
    """

    def __init__(
        self,
        world: World,
        context: foxglove.Context,
        assets: AssetLibrary,
        on_time: Callable[[int], None],
        stream_period_s: float | None = None,
    ) -> None:
        self._world = world
        self._stream_period_s = stream_period_s
        self._context = context
        self._assets = assets
        self._on_time = on_time
        self._topics: dict[str, _TopicChannel] = {}
        self._descriptions: dict[str, _DescriptionChannel] = {}
        #: Channel id -> what it carries (read in the stepping thread only).
        self._by_id: dict[int, _TopicChannel | _DescriptionChannel] = {}
        self._watch: Subscription | None = None
        self._scene = SceneObjects(world, context)
        self._last_time_ns = -1
        self._last_repeat_s = time.monotonic()
        self._skipped: dict[str, int] = {}
        self._closed = False
        #: Messages handed to the server so far (descriptions included).
        self.sent = 0

    # -- what is served ---------------------------------------------------------------
    @property
    def topics(self) -> list[str]:
        """The topics with a channel now, sorted."""
        descriptions = (topics.robot_description(name) for name in self._descriptions)
        return sorted([*self._topics, *descriptions, topics.SCENE_OBJECTS])

    @property
    def listened(self) -> list[str]:
        """The bus topics this server is subscribed to now (some client listens), sorted."""
        return sorted(t for t, entry in self._topics.items() if entry.subscription is not None)

    @property
    def skipped(self) -> dict[str, int]:
        """Per topic, messages that could not be encoded (normally empty)."""
        return dict(self._skipped)

    def start(self) -> None:
        """Open the channels of what the world has now, and watch for arms to come."""
        self._watch = self._world.bus.subscribe(topics.BRINGUP, self._on_bringup)
        self.refresh()

    def close(self) -> None:
        """Cancel every bus subscription and close every channel; idempotent."""
        if self._closed:
            return
        self._closed = True
        if self._watch is not None:
            self._watch.cancel()
        for topic in list(self._topics):
            self._close_topic(topic)
        for name in list(self._descriptions):
            self._close_description(name)
        self._scene.close()

    # -- arms and topics coming and going (stepping thread) ---------------------------
    def _on_bringup(self, event: Any) -> None:
        self.refresh()

    def refresh(self) -> None:
        """Open channels for new topics and arms, close those of topics and arms gone."""
        if self._closed:
            return
        bus_topics = self._world.bus.topics
        for topic in [t for t in self._topics if t not in bus_topics]:
            self._close_topic(topic)
        arms = self._world.arms
        for name in [n for n, d in self._descriptions.items() if arms.get(n) is not d.arm]:
            self._close_description(name)
        for topic, message_type in bus_topics.items():
            if topic not in self._topics:
                self._open_topic(topic, message_type)
        for name, arm in arms.items():
            if name not in self._descriptions:
                self._open_description(arm)
        self._scene.refresh()

    def _open_topic(self, topic: str, message_type: type) -> None:
        encode = encoder_for(message_type)
        channel = self._channel(topic, encode.schema, message_type.__name__)
        streamed = topic == topics.TF or issubclass(message_type, STREAMED_TYPES)
        entry = _TopicChannel(topic, channel, encode, streamed)
        self._topics[topic] = entry
        self._by_id[channel.id()] = entry

    def _open_description(self, arm: Arm) -> None:
        topic = topics.robot_description(arm.name)
        encode = StringEncoder()
        channel = self._channel(topic, encode.schema, "str")
        entry = _DescriptionChannel(arm, channel, encode(self._assets.add_arm(arm)))
        entry.watch = self._world.bus.subscribe(
            topics.status(arm.name), self._on_status, on_gone=self._on_gone
        )
        self._descriptions[arm.name] = entry
        self._by_id[channel.id()] = entry

    def _channel(self, topic: str, schema: MessageSchema, type_name: str) -> foxglove.Channel:
        return foxglove.Channel(
            topic,
            schema=sdk_schema(schema),
            message_encoding=JSON,
            context=self._context,
            metadata={"armfleet_type": type_name},
        )

    def _close_topic(self, topic: str) -> None:
        entry = self._topics.pop(topic)
        if entry.subscription is not None:
            entry.subscription.cancel()
        self._by_id.pop(entry.channel.id(), None)
        entry.channel.close()

    def _close_description(self, name: str) -> None:
        entry = self._descriptions.pop(name)
        if entry.watch is not None:
            entry.watch.cancel()
        self._assets.remove_arm(name)
        self._by_id.pop(entry.channel.id(), None)
        entry.channel.close()

    def _on_status(self, status: Any) -> None:
        # A topic first published after its arm's bring-up (the status itself) gets its
        # channel on the next tick.
        if len(self._world.bus.topics) != len(self._topics):
            self.refresh()
        else:
            self._scene.refresh()  # objects added or removed since
        now = stamp_ns(self._world.time)
        if now - self._last_time_ns >= stamp_ns(TIME_PERIOD_S):
            self._tick(now)
        self._repeat_latched()

    def _repeat_latched(self) -> None:
        """Send the latched topics' messages again every :data:`LATCHED_REPEAT_S`, while a
        client listens: an app subscribes once per topic for all its panels, so a panel
        mounted after the subscription (Raw Messages of ``/tf_static`` beside the 3D panel)
        would otherwise never see them."""
        wall = time.monotonic()
        if wall - self._last_repeat_s < LATCHED_REPEAT_S:
            return
        self._last_repeat_s = wall
        for entry in self._topics.values():
            if entry.subscription is not None and entry.channel.has_sinks():
                for message in self._world.bus.latched(entry.topic):
                    self._deliver(entry, message)

    def _on_gone(self, topic: str, reason: str) -> None:
        self.refresh()

    # -- clients subscribing (server thread -> stepping thread) -----------------------
    def on_subscribe(self, channel_id: int) -> None:
        """A client subscribed to channel ``channel_id`` (called in the server's thread)."""
        self._hand_over(functools.partial(self._sync, channel_id, True))

    def on_unsubscribe(self, channel_id: int) -> None:
        """A client unsubscribed from channel ``channel_id`` or left (server's thread)."""
        self._hand_over(functools.partial(self._sync, channel_id, False))

    def _hand_over(self, work: Callable[[], None]) -> None:
        try:
            self._world.submit(work)
        except WorldClosed:
            return  # nothing left to subscribe to
        except queue.Full:
            logger.warning(
                "foxglove: the world has too many requests waiting; a subscription "
                "change was dropped"
            )

    def _sync(self, channel_id: int, subscribed: bool) -> None:
        """Listen to the bus topic of ``channel_id`` if and only if a client does; send
        the latched messages to a client that just subscribed."""
        if self._closed:
            return
        if channel_id == self._scene.channel_id:
            if subscribed:
                self._scene.resend()
            return
        entry = self._by_id.get(channel_id)
        if entry is None:
            return
        wanted = entry.channel.has_sinks()
        if isinstance(entry, _DescriptionChannel):
            if subscribed and wanted:
                now = stamp_ns(self._world.time)
                self._tick(now)
                entry.channel.log(entry.message, log_time=now)
                self.sent += 1
            return
        if wanted and entry.subscription is None:  # the bus replays latched messages
            deliver = functools.partial(self._deliver, entry)
            period = self._stream_period_s if entry.streamed else None
            entry.subscription = self._world.bus.subscribe(entry.topic, deliver, period_s=period)
        elif wanted and subscribed:
            for message in self._world.bus.latched(entry.topic):
                self._deliver(entry, message)
        elif not wanted and entry.subscription is not None:
            entry.subscription.cancel()
            entry.subscription = None

    def _deliver(self, entry: _TopicChannel, message: Any) -> None:
        """Encode and hand one bus message to the server (stepping thread; cheap)."""
        channel = entry.channel
        if not channel.has_sinks():
            return
        try:
            data = entry.encode(message)
        except Exception as exc:  # never let a viewer stop the simulation
            skipped = self._skipped.get(entry.topic, 0)
            if not skipped:
                logger.warning("foxglove: cannot encode a message of %s: %s", entry.topic, exc)
            self._skipped[entry.topic] = skipped + 1
            return
        now = stamp_ns(self._world.time)
        self._tick(now)
        channel.log(data, log_time=now)
        self.sent += 1

    def _tick(self, now: int) -> None:
        """Send the clock ``now`` [ns] if it moved since last sent: before the messages of
        a new instant, so that an app stamping each message with the server's latest time
        (Lichtblick, Foxglove) stamps it with its own log time."""
        if now > self._last_time_ns:
            self._last_time_ns = now
            self._on_time(now)
