"""``armfleet replay RUN.mcap``: a recording back in the MeshCat viewer, or as an HTML file.

A live replay waits for a browser before its clock starts (``--no-wait`` starts at
once): the recording's opening (its arms coming up) is sent to the viewer, and the
replay starts once a page reports them shown. ``--loop`` plays it again and again.
"""

from __future__ import annotations

import argparse
import signal
import time
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from armfleet.cli.ctrl_c import let_ctrl_c_stop
from armfleet.cli.number_arguments import port, replay_speed
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.path_arguments import path_text
from armfleet.recording import Recording, ReplayPlayer, export_html, open_recording
from armfleet.recording.replay import start_replay_viewer

if TYPE_CHECKING:
    from armfleet.viewer import Viewer

#: How often the held viewer checks for Ctrl-C [s].
HOLD_SLEEP_S = 0.5
#: How often a waiting replay asks the viewer for browsers [s].
BROWSER_POLL_S = 0.2
#: How long a connected page may take to report the arms shown before the replay
#: starts anyway (a software-rendered page takes 10-15 s for two Pandas) [s].
SHOWN_CAP_S = 120.0


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "replay",
        help="play a recording back in the viewer (or export it as HTML), without simulating",
        description="Play a recording (armfleet spawn/launch --record RUN.mcap) back in the "
        "MeshCat viewer: the recorded arms at their recorded joint positions and times, "
        "nothing simulated. The replay starts once a browser shows the arms (--no-wait: at "
        "once). With --html, write the standalone HTML replay instead.",
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
        "--no-wait", action="store_true",
        help="start at once (default: wait until a browser shows the recorded arms)",
    )  # fmt: skip
    ending = parser.add_mutually_exclusive_group()
    ending.add_argument(
        "--exit-at-end", action="store_true",
        help="exit when the replay ends (default: keep the viewer open until Ctrl-C)",
    )  # fmt: skip
    ending.add_argument(
        "--loop", action="store_true", help="play the recording again and again until Ctrl-C"
    )
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
    let_ctrl_c_stop()  # it may wait for a browser, or loop, until Ctrl-C
    viewer = start_replay_viewer(args.viewer_port)
    try:
        print(f"viewer: {viewer.url}", flush=True)
        player = ReplayPlayer(recording, viewer)
        arms = ", ".join(recording.arm_names)
        replaying = f"replaying {recording.duration_s:.3f} s of {arms} at {args.speed:g}x"

        def start() -> None:
            _say(args, f"{_wait_for_browser(viewer)}; {replaying}")

        if args.no_wait:
            _say(args, replaying)
        else:  # an instruction, printed even with --quiet
            print(
                f"waiting for a browser: open {viewer.url} to start the replay "
                "(--no-wait starts it at once)",
                flush=True,
            )
        duration = player.play(speed=args.speed, on_opened=None if args.no_wait else start)
        while args.loop:
            _say(args, f"replay finished at t={duration:.3f}s; replaying again (Ctrl-C to exit)")
            # The arms come up again before the clock restarts, as the first time.
            duration = player.play(speed=args.speed, on_opened=lambda: None)
        viewer.refresh()
        _say(args, f"replay finished at t={duration:.3f}s")
        if not args.exit_at_end:
            _say(
                args,
                "the viewer stays open; Ctrl-C to exit (--loop plays the recording again "
                "and again)",
            )
            while True:
                time.sleep(HOLD_SLEEP_S)
    except KeyboardInterrupt:
        _say(args, "interrupted")
    finally:
        viewer.close()
    return 0


def _wait_for_browser(viewer: Viewer) -> str:
    """Wait until a page shows the arms sent so far; returns what ended the wait.

    Raises:
        ViewerError: the viewer's server is gone.
    """
    connected_at: float | None = None
    while True:
        browsers = viewer.browsers
        if browsers.shown:
            return "a browser shows the arms"
        if not browsers.connected:
            connected_at = None
        elif connected_at is None:
            connected_at = time.monotonic()
        elif time.monotonic() - connected_at > SHOWN_CAP_S:
            return f"a browser connected but showed no arms within {SHOWN_CAP_S:g} s"
        time.sleep(BROWSER_POLL_S)


def _say(args: argparse.Namespace, line: str) -> None:
    if not args.quiet:
        print(line, flush=True)
