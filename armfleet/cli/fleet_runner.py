"""Run a :class:`FleetSpec` from the command line: bring-up lines, live API, status, clean
shutdown."""

from __future__ import annotations

import argparse
import signal
import sys
import time
from types import FrameType
from typing import TYPE_CHECKING

from armfleet import topics
from armfleet.cli.api_options import check_api_arguments, start_api
from armfleet.cli.ctrl_c import let_ctrl_c_stop
from armfleet.cli.foxglove_options import start_foxglove
from armfleet.cli.listen_ports import check_run_ports
from armfleet.cli.record_option import RunRecording
from armfleet.cli.ros_options import start_ros
from armfleet.cli.status_line import status_line
from armfleet.cli.world_loop import run_world
from armfleet.messages import BringupEvent, BringupStage

if TYPE_CHECKING:  # types only; the simulator loads when a world starts
    from armfleet.spec import FleetSpec
    from armfleet.world import World


def run_fleet(spec: FleetSpec, args: argparse.Namespace) -> int:
    """Bring the spec's arms up, run until ``--duration`` or Ctrl-C/SIGTERM, close cleanly."""
    from armfleet.services.run_state import RunState
    from armfleet.world.launch import launch

    if hasattr(args, "api_port"):
        check_api_arguments(args)
    recording = RunRecording(args.record, spec, quiet=args.quiet)
    viewer = (spec.world.viewer and not args.no_viewer) or recording.needs_viewer
    realtime = spec.world.realtime if args.realtime is None else args.realtime
    check_run_ports(args, viewer)

    def say(line: str) -> None:
        if not args.quiet:
            print(line, flush=True)

    def on_term(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)  # SIGTERM shuts down like Ctrl-C
    let_ctrl_c_stop()  # this command runs until Ctrl-C (or kill -INT)

    def before_spawn(world: World) -> None:
        recording.start(world)
        if viewer:
            if world.viewer is not None:
                print(f"viewer: {world.viewer.url}", flush=True)
            else:
                print(f"armfleet: viewer not started: {world.viewer_error}", file=sys.stderr)

        def on_bringup(event: BringupEvent) -> None:
            stamps = f"(t={event.stamp:.3f}s, {event.wall_time:.2f}s)"
            line = f"[{event.arm}] {event.stage.value} {stamps}"
            arm = world.arms.get(event.arm)
            choice = arm.description.home_choice if arm is not None else None
            if event.stage is BringupStage.SPAWNED and choice is not None:  # a model file's
                line += f", {choice.clause}"
            say(line)

        world.bus.subscribe(topics.BRINGUP, on_bringup)

    finished = ""  # the closing line of a run that reached its --duration
    try:
        started = time.perf_counter()
        world = launch(spec, viewer=viewer, viewer_port=args.viewer_port, before_spawn=before_spawn)
        try:
            say(f"{len(spec.arms)} arm(s) ready in {time.perf_counter() - started:.2f}s")
            # The API starts once the spec's arms are up: a client's spawn then never
            # lands in the middle of the spec's bring-up.
            run_state = RunState()
            foxglove = start_foxglove(world, args)  # closed with the world if the API fails
            ros = start_ros(world, args)
            server = start_api(world, run_state, args)
            try:
                run_world(
                    world,
                    run_state,
                    args.duration,
                    realtime,
                    on_status=lambda rtf: say(status_line(world, rtf)),
                    on_pause=lambda paused: say(
                        f"{'paused' if paused else 'resumed'} at t={world.time:.3f}s"
                    ),
                )
                finished = (
                    f"ran --duration {args.duration:g} s (t={world.time:.3f}s, "
                    f"{time.perf_counter() - started:.2f} s wall in all); shut down cleanly"
                )
            finally:
                if foxglove is not None:
                    foxglove.close()
                if ros is not None:
                    ros.close()
                if server is not None:
                    server.close()
        finally:
            recording.save(world)
            world.close()
    except KeyboardInterrupt:
        say("interrupted; shut down cleanly")
    finally:
        recording.close()  # an MCAP file is completed even if bring-up failed
    if finished:
        say(finished)
    return 0
