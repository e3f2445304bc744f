"""``armfleet info RUN.mcap``: what a recording holds (topics, counts, duration, arms).

``armfleet info`` without a file still describes the running world; this
module only adds the optional file argument to that command.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TYPE_CHECKING

from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.path_arguments import path_text

if TYPE_CHECKING:  # the recording reader loads only to describe a recording
    from armfleet.recording import Recording


def extend_info_parser(parser: OneLineParser) -> None:
    """Give ``armfleet info`` an optional recording to describe instead of the running world."""
    world_info: Callable[[argparse.Namespace], int] = parser.get_default("run")
    parser.add_argument(
        "recording", nargs="?", type=path_text, default=None, metavar="RUN.mcap",
        help="describe this recording instead of the running world",
    )  # fmt: skip
    parser.description = (
        "Time, step, real-time factor and arms of the running world; with RUN.mcap, the "
        "topics, message counts, duration and arms of that recording."
    )

    def run(args: argparse.Namespace) -> int:
        if args.recording is None:
            return world_info(args)
        if args.connect is not None:
            raise UsageError("give a recording or --connect, not both")
        from armfleet.recording import open_recording

        print(describe(open_recording(args.recording)))
        return 0

    parser.set_defaults(run=run)


def describe(recording: Recording) -> str:
    """The text ``armfleet info RUN.mcap`` prints."""
    size_mb = recording.path.stat().st_size / 1e6
    state = (
        "complete"
        if recording.complete
        else "INCOMPLETE: the recorder did not finish (killed?) and the file has no index; "
        f"read up to its last whole record; 'armfleet recover {recording.path}' writes a "
        "complete copy that every MCAP reader can open"
    )
    run = recording.run
    lines = [f"file:        {recording.path} ({size_mb:.2f} MB, {state})"]
    if run:
        lines.append(
            f"recorded:    {run.get('started_utc', '?')} by armfleet "
            f"{run.get('armfleet_version', '?')}, dt {run.get('dt_s', '?')} s"
        )
    if recording.start_ns is not None and recording.end_ns is not None:
        lines.append(
            f"time:        {recording.start_ns / 1e9:.3f} .. {recording.end_ns / 1e9:.3f} s "
            f"simulated (duration {recording.duration_s:.3f} s)"
        )
    else:
        lines.append("time:        (no messages)")
    lines.append(f"messages:    {recording.message_count} on {len(recording.topics)} topics")
    arms = []
    for arm in recording.arms:
        left = "" if arm.removed_ns is None else f", removed at t={arm.removed_ns / 1e9:.3f}s"
        arms.append(f"{arm.name} ({arm.model} at {arm.pose}{left})")
    lines.append(f"arms:        {', '.join(arms) or '(none)'}")
    if recording.spec_text is not None:
        source = run.get("spec_source") or "Python"
        lines.append(f"launch spec: from {source} (attachment launch_spec.yaml)")
    lines.append(f"attachments: {', '.join(recording.attachment_names) or '(none)'}")
    lines.append("topics:")
    width = max((len(topic) for topic in recording.topics), default=5)
    types = max((len(info.schema_name) for info in recording.topics.values()), default=4)
    lines.append(f"  {'topic':<{width}}  {'type':<{types}}  {'messages':>8}  {'mean rate':>10}")
    duration = recording.duration_s
    for topic in sorted(recording.topics):
        info = recording.topics[topic]
        rate = (
            f"{(info.message_count - 1) / duration:.1f} Hz"
            if duration and info.message_count > 1
            else "-"
        )
        lines.append(
            f"  {topic:<{width}}  {info.schema_name:<{types}}  {info.message_count:>8}  {rate:>10}"
        )
    return "\n".join(lines)
