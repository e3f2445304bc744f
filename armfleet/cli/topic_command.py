"""``armfleet topic list`` and ``armfleet topic echo TOPIC [--once] [--rate HZ]``."""

from __future__ import annotations

import argparse
import contextlib
import math
import queue
import sys
from typing import Any

import yaml

from armfleet.cli.api_options import add_connect_arguments, connect_from
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.remote import ConnectionLost
from armfleet.remote.codec import to_wire

#: Messages ``echo`` holds for the terminal before dropping the oldest.
ECHO_QUEUE = 100


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
    echo.set_defaults(run=echo_topic)
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

    with connect_from(args) as client:
        subscription = client.subscribe(args.topic, keep, rate_hz=rate)
        while True:  # until --once, Ctrl-C, or a closed pipe (armfleet ... | head)
            try:
                message = received.get(timeout=0.25)
            except queue.Empty:
                if not subscription.active:
                    raise subscription.error or ConnectionLost("the world went away") from None
                continue
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
