"""``armfleet topic list`` and ``armfleet topic echo TOPIC [--once] [--rate HZ] [--timeout S]``.

``echo --timeout S`` bounds the whole command: it ends within about S seconds
whatever the world does (silent topic, topic removed, world gone or hung).
Without it, ``echo`` runs until Ctrl-C, its topic goes away, or the world does.

A topic may be silent for long (``/collisions`` publishes only while something touches):
when nothing has come within :data:`LISTENING_HINT_S` of subscribing, ``echo`` says once, on
stderr, that it is listening (not with ``--once``, whose caller waits for one message).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import queue
import sys
import time
from typing import Any

import yaml

from armfleet.cli.api_options import add_connect_arguments, connect_from
from armfleet.cli.ctrl_c import let_ctrl_c_stop
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.remote import ConnectionLost
from armfleet.remote.client import DEFAULT_TIMEOUT_S
from armfleet.services.codec import to_wire
from armfleet.services.errors import RequestTimeout

#: Messages ``echo`` holds for the terminal before dropping the oldest.
ECHO_QUEUE = 100
#: Silence after subscribing before ``echo`` says it is listening [s].
LISTENING_HINT_S = 1.0


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "topic",
        help="list or echo the topics of the running world",
        description="List or echo the topics of the running world.",
    )
    actions = parser.add_subparsers(dest="action", required=True, parser_class=OneLineParser)
    listing = actions.add_parser("list", help="the topics and their message types")
    listing.add_argument("-t", "--show-types", action="store_true", help="show message types")
    add_connect_arguments(listing)
    listing.set_defaults(run=list_topics)
    echo = actions.add_parser("echo", help="print the messages of a topic")
    echo.add_argument("topic", metavar="TOPIC", help="e.g. /bob/joint_states")
    echo.add_argument("--once", action="store_true", help="print one message and exit")
    echo.add_argument(
        "--rate", type=float, default=None, metavar="HZ",
        help="print at most HZ messages per second (default: as many as the terminal takes)",
    )  # fmt: skip
    add_connect_arguments(echo)
    for action in echo._actions:
        if action.dest == "timeout":
            action.help = (
                "end within about S seconds whatever happens (with --once: an error if no "
                "message came); default: run until Ctrl-C, and wait "
                f"{DEFAULT_TIMEOUT_S:g} s for each answer of the world"
            )
    echo.set_defaults(run=echo_topic, timeout=None)  # None: --timeout not given
    actions.metavar = "{" + ",".join(actions.choices) + "}"  # named in a missing-action error
    parser.commands = tuple(actions.choices)


def list_topics(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        topics = client.topics()
    for topic in topics.values():
        print(f"{topic.topic} [{topic.type_name}]" if args.show_types else topic.topic)
    return 0


def echo_topic(args: argparse.Namespace) -> int:
    rate = args.rate
    if rate is not None and not (math.isfinite(rate) and rate > 0):
        raise UsageError(f"--rate {rate} is invalid; give messages per second > 0")
    received: queue.Queue[Any] = queue.Queue(ECHO_QUEUE)

    def keep(message: Any) -> None:
        while True:
            try:
                received.put_nowait(message)
                return
            except queue.Full:  # the terminal is slower: drop the oldest
                with contextlib.suppress(queue.Empty):
                    received.get_nowait()

    limit: float | None = args.timeout
    if limit is None:
        let_ctrl_c_stop()  # it runs until Ctrl-C
    started = time.monotonic()
    # Each answer of the world waits at most the time left, so that connecting and
    # subscribing fit in the limit too (the subscription asks twice: stream, subscribe).
    request_timeout = DEFAULT_TIMEOUT_S if limit is None else limit
    with connect_from(argparse.Namespace(**vars(args) | {"timeout": request_timeout})) as client:
        if limit is not None:
            client.timeout = max(1e-3, 0.5 * (limit - (time.monotonic() - started)))
        subscription = client.subscribe(args.topic, keep, rate_hz=rate)
        hint_at = None if args.once else time.monotonic() + LISTENING_HINT_S
        while True:  # until --once, --timeout, Ctrl-C, or a closed pipe (armfleet ... | head)
            if hint_at is not None and time.monotonic() >= hint_at:
                hint_at = None
                print(
                    f"listening on {args.topic}; nothing published on it yet (Ctrl-C to stop)",
                    file=sys.stderr,
                    flush=True,
                )
            wait = 0.25
            if limit is not None:
                left = limit - (time.monotonic() - started)
                if left <= 0:
                    if args.once:
                        raise RequestTimeout(f"no message on {args.topic} within {limit:g} s")
                    return 0
                wait = min(wait, left)
            try:
                message = received.get(timeout=wait)
            except queue.Empty:
                if not subscription.active:
                    raise subscription.error or ConnectionLost("the world went away") from None
                continue
            hint_at = None  # messages show it is listening
            sys.stdout.write(format_message(message) + "---\n")
            sys.stdout.flush()
            if args.once:
                return 0


def format_message(message: Any) -> str:
    """A message as YAML, vectors on one line (like ``ros2 topic echo``)."""
    text: str = yaml.safe_dump(
        to_wire(message), default_flow_style=None, sort_keys=False, width=1_000_000
    )
    return text
