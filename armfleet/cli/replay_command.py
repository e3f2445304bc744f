"""``armfleet replay RUN.mcap``: a recording back in the MeshCat viewer, or as an HTML file."""

from __future__ import annotations

import argparse
import signal
import time
from pathlib import Path
from types import FrameType

from armfleet.cli.number_arguments import port, replay_speed
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.path_arguments import path_text
from armfleet.recording import Recording, ReplayPlayer, export_html, open_recording
from armfleet.recording.replay import start_replay_viewer

#: How often the held viewer checks for Ctrl-C [s].
HOLD_SLEEP_S = 0.5


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "replay",
        help="play a recording back in the viewer (or export it as HTML), without simulating",
        description="Play a recording (armfleet spawn/launch --record RUN.mcap) back in the "
        "MeshCat viewer: the recorded arms at their recorded joint positions and times, "
        "nothing simulated. With --html, write the standalone HTML replay instead.",
    )
    parser.add_argument("recording", type=path_text, metavar="RUN.mcap", help="the recording")
    parser.add_argument(
        "--html", type=path_text, default=None, metavar="OUT.html",
        help="write the standalone HTML replay (plays from file://) and exit",
    )  # fmt: skip
    parser.add_argument(
        "--speed", type=replay_speed, default=1.0, metavar="X",
        help="playback speed, times real time (default 1)",
    )  # fmt: skip
    parser.add_argument(
        "--viewer-port", type=port, default=None, metavar="PORT",
        help="web port of the viewer (default: a free port)",
    )  # fmt: skip
    parser.add_argument(
        "--exit-at-end", action="store_true",
        help="exit when the replay ends (default: keep the viewer open until Ctrl-C)",
    )  # fmt: skip
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.html is not None:
        target = Path(args.html)
        if target.suffix.lower() != ".html":
            raise UsageError(f"--html {args.html}: name an .html file")
        if not target.parent.is_dir():
            raise UsageError(f"--html {args.html}: the folder {target.parent} does not exist")
    recording = open_recording(args.recording)
    if args.html is not None:
        path = export_html(recording, args.html)
        _say(args, f"replay saved to {path}")
        return 0
    return _play_live(recording, args)


def _play_live(recording: Recording, args: argparse.Namespace) -> int:
    def on_term(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)  # SIGTERM ends like Ctrl-C
    viewer = start_replay_viewer(args.viewer_port)
    try:
        print(f"viewer: {viewer.url}", flush=True)
        player = ReplayPlayer(recording, viewer)
        arms = ", ".join(recording.arm_names)
        _say(args, f"replaying {recording.duration_s:.3f} s of {arms} at {args.speed:g}x")
        duration = player.play(speed=args.speed)
        viewer.refresh()
        _say(args, f"replay finished at t={duration:.3f}s")
        if not args.exit_at_end:
            _say(args, "the viewer stays open; Ctrl-C to exit")
            while True:
                time.sleep(HOLD_SLEEP_S)
    except KeyboardInterrupt:
        _say(args, "interrupted")
    finally:
        viewer.close()
    return 0


def _say(args: argparse.Namespace, line: str) -> None:
    if not args.quiet:
        print(line, flush=True)
