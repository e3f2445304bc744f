"""``armfleet spawn`` when a world already runs: add the arms to it instead of a new world."""

from __future__ import annotations

import argparse
import contextlib
import queue
import sys
import time

from armfleet import topics
from armfleet.checks.network_address import DEFAULT_BIND
from armfleet.cli.parser import UsageError
from armfleet.cli.ros_options import ROS_DETAILS
from armfleet.messages import BringupEvent, BringupStage
from armfleet.remote import Client, NoWorldFound, connect, runtime_file
from armfleet.remote.client_quotas import RAISED_BY, ClientQuotas
from armfleet.remote.runtime_file import WorldEntry
from armfleet.spec import FleetSpec

#: How long an unasked-for world in the runtime file may take to answer [s].
PROBE_TIMEOUT_S = 2.0
#: Wait for the last bring-up event once the spawn has returned [s].
EVENT_GRACE_S = 2.0
#: Options that only make sense for a new world: (flag, attribute, default).
_NEW_WORLD_OPTIONS = (
    ("--duration", "duration", None),
    ("--realtime/--fast", "realtime", None),
    ("--no-viewer", "no_viewer", False),
    ("--viewer-port", "viewer_port", None),
    ("--record", "record", None),
    ("--api-bind", "api_bind", DEFAULT_BIND),
    ("--api-port", "api_port", 0),
    ("--no-api", "no_api", False),
    ("--foxglove", "foxglove", None),
    ("--foxglove-bind", "foxglove_bind", DEFAULT_BIND),
    ("--foxglove-rate", "foxglove_rate", None),
    ("--ros", "ros", False),
    *ROS_DETAILS,
    *(
        (option, f"quota_{quota}", getattr(ClientQuotas(), quota))
        for quota, option in RAISED_BY.items()
    ),
)


def running_world(args: argparse.Namespace) -> Client | None:
    """The world to add the arms to: ``--connect``'s, else the runtime file's if it
    answers; None for a new world (``--new-world``, or none running).

    Joining a world prints, first (unless ``--quiet``), which world it is: who else
    runs it may not be obvious (any process of the same user registers there)."""
    if args.new_world:
        if args.connect is not None:
            raise UsageError("--new-world and --connect exclude each other")
        return None
    entry: WorldEntry | None = None
    if args.connect is not None:
        client = connect(args.connect, timeout=args.timeout)
    else:
        entry = runtime_file.live_entry()
        if entry is None:
            return None
        try:
            client = connect(entry.address, timeout=PROBE_TIMEOUT_S)
        except NoWorldFound:
            print(
                f"armfleet: note: the world named by {entry.path} (process {entry.pid}) does not "
                "answer; starting a new one",
                file=sys.stderr,
            )
            return None
        client.timeout = args.timeout
    given = [flag for flag, name, default in _NEW_WORLD_OPTIONS if getattr(args, name) != default]
    if given:
        client.close()
        raise UsageError(
            f"{', '.join(given)} set options of a new world, but a world is running at "
            f"{client.address}; drop them to add the arms to it, or add --new-world"
        )
    if not args.quiet:
        try:
            print(joining_line(client, entry), flush=True)
        except BaseException:
            client.close()
            raise
    return client


def joining_line(client: Client, entry: WorldEntry | None) -> str:
    """E.g. ``joining the running world at tcp://127.0.0.1:41234 (process 4242, started
    2026-11-23 05:52:10, 12 min ago; arms: bob, toby); add --new-world for a separate
    world``. ``entry``: the runtime file's, when the world was found through it."""
    info = client.info()
    facts = [f"process {info.pid}"]
    if entry is None:  # --connect: the runtime file may name the same world
        entry = runtime_file.live_entry()
    started = entry.started_at if entry is not None and entry.pid == info.pid else None
    if started is not None:
        stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(started))
        facts.append(f"started {stamp}, {_age(time.time() - started)} ago")
    arms = ", ".join(info.arms) or "none yet"
    return (
        f"joining the running world at {client.address} ({', '.join(facts)}; arms: {arms}); "
        "add --new-world for a separate world"
    )


def _age(seconds: float) -> str:
    """``40 s``, ``12 min``, ``3.5 h``, ``2.0 days``."""
    if seconds < 120:
        return f"{max(seconds, 0):.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 172800:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def add_to_world(client: Client, spec: FleetSpec, quiet: bool) -> int:
    """Spawn the spec's arms in the running world, one after the other, showing their stages."""
    names = {arm.name for arm in spec.arms}
    events: queue.Queue[BringupEvent] = queue.Queue()
    subscription = client.subscribe(topics.BRINGUP, events.put, queue_size=1000)
    try:
        for arm in spec.arms:
            client.spawn(arm.name, arm.model, arm.pose, **arm.options.keywords())
            _show_stages(events, arm.name, names, quiet)
            if not quiet:
                home = client.call("arm", {"name": arm.name}).get("home", "")  # a model file's
                print(
                    f"{arm.name} ready in the world at {client.address}"
                    + (f" ({home})" if home else ""),
                    flush=True,
                )
    finally:
        subscription.cancel()
    return 0


def _show_stages(events: queue.Queue[BringupEvent], name: str, ours: set[str], quiet: bool) -> None:
    """Print our arms' stages until ``name`` is ready (events may trail the reply a little)."""
    while True:
        try:
            event = events.get(timeout=EVENT_GRACE_S)
        except queue.Empty:
            return
        if event.arm in ours and not quiet:
            with contextlib.suppress(BrokenPipeError):
                print(
                    f"[{event.arm}] {event.stage.value} (t={event.stamp:.3f}s, "
                    f"{event.wall_time:.2f}s)",
                    flush=True,
                )
        if event.arm == name and event.stage is BringupStage.READY:
            return
