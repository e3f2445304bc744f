"""The MeshCat viewer of a world: live in the browser, exportable as a replay.

:func:`start_viewer` starts it (``World(viewer=True)`` does); the world calls
:meth:`Viewer.add_arm` when an arm is ready and :meth:`Viewer.tick` after
every physics step. A tick costs next to nothing unless a display update is
due (~30 Hz of wall time) or a replay frame (30 Hz of simulated time). An
update is sent without waiting for anything (:mod:`armfleet.viewer.live_link`),
so neither the server nor a browser can slow the simulation down; once the
simulation pauses, a background thread sends the poses it came to rest in. A
viewer that fails (its server died or hangs) stops itself; the simulation goes
on and :attr:`Viewer.error` says why. While an arm runs a planned motion, its tool
path is drawn under the arm's node (:mod:`armfleet.viewer.plan_lines`).

The camera frames the arms before their meshes are sent: the arms a launch announces
(:meth:`Viewer.expect_arms`) from the first frame, any other arm as it comes; the page
shows a loading line until the meshes are all in it (:mod:`armfleet.viewer.arrivals`).

Only the standard library and numpy are imported with this module: MeshCat,
Pinocchio's visualizer, ZMQ and tornado load when a viewer starts.
"""

from __future__ import annotations

import logging
import math
import threading
import time
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from armfleet.checks.flags import flag
from armfleet.viewer.errors import ViewerError

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.messages import PlannedMotion
    from armfleet.objects import WorldObject
    from armfleet.viewer.arm_visual import ArmVisual
    from armfleet.viewer.arrivals import Arrivals
    from armfleet.viewer.commands import Updates
    from armfleet.viewer.connection import BridgeConnection
    from armfleet.viewer.idle_refresher import IdleRefresher
    from armfleet.viewer.live_link import LiveLink
    from armfleet.viewer.object_visual import ObjectVisual
    from armfleet.viewer.plan_lines import PlanLines
    from armfleet.viewer.recorder import Recorder
    from armfleet.viewer.scene import Stage
    from armfleet.viewer.server import ViewerServer
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: Live updates per second of wall time.
DISPLAY_RATE_HZ = 30.0
#: Time without display updates after which the resting poses are sent [s].
PAUSE_S = 0.1
#: Time live updates may go unanswered before the viewer checks its server [s].
STALL_TIMEOUT_S = 5.0
#: Time a save may wait for the server's scene [s].
SCENE_TIMEOUT_S = 60.0


class BrowserCount(NamedTuple):
    """The pages open on a viewer.

    Attributes:
        connected: pages connected to the server.
        shown: pages among them that reported every mesh sent so far shown.
    """

    connected: int
    shown: int


def start_viewer(
    port: int | None = None, *, show_frames: bool = False, show_targets: bool = True
) -> tuple[Viewer | None, str | None]:
    """Start a viewer; never raises because its server could not start.

    Args:
        port: web port on 127.0.0.1; a free one if None.
        show_frames: show each arm's ``base_link`` and ``tool0`` frames.
        show_targets: show a marker at ``tool0`` of each arm's motion target.

    Returns:
        ``(viewer, None)``, or ``(None, reason)`` if it could not start.
    """
    try:
        return Viewer(port, show_frames=show_frames, show_targets=show_targets), None
    except ImportError as exc:
        reason = f"viewer unavailable: {exc}"
    except ViewerError as exc:
        reason = f"viewer could not start: {exc}"
    logger.warning("%s", reason)
    return None, reason


class Viewer:
    """A MeshCat server on 127.0.0.1 showing every arm of one world.

    Prefer :func:`start_viewer`, which reports instead of raising.

    Args:
        port: web port on 127.0.0.1; a free one if None.
        show_frames: show each arm's ``base_link`` and ``tool0`` frames.
        show_targets: show a marker at ``tool0`` of each arm's motion target.
        display_rate_hz: live updates per second of wall time.

    Raises:
        ViewerError: the server could not start or does not answer, or a bad rate.
    """

    def __init__(
        self,
        port: int | None = None,
        *,
        show_frames: bool = False,
        show_targets: bool = True,
        display_rate_hz: float = DISPLAY_RATE_HZ,
    ) -> None:
        show_frames = flag(show_frames, "show_frames")
        show_targets = flag(show_targets, "show_targets")
        if not (math.isfinite(display_rate_hz) and 0 < display_rate_hz <= 1000):
            raise ViewerError(
                f"display rate {display_rate_hz} Hz is invalid; choose one in (0, 1000] Hz"
            )
        import zmq

        with warnings.catch_warnings():  # meshcat 0.3 imports a deprecated pyzmq module
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat

        from armfleet.viewer.arrivals import Arrivals
        from armfleet.viewer.idle_refresher import IdleRefresher
        from armfleet.viewer.live_link import LiveLink
        from armfleet.viewer.plan_lines import PlanLines
        from armfleet.viewer.recorder import Recorder
        from armfleet.viewer.scene import Stage
        from armfleet.viewer.server import ViewerServer

        self._server: ViewerServer = ViewerServer.start(port)
        self._context: Any = zmq.Context()
        self._connection: BridgeConnection | None = None
        self._link: LiveLink | None = None
        self._refresher: IdleRefresher | None = None
        self._plans: PlanLines | None = None
        self._visuals: dict[str, ArmVisual] = {}
        self._objects: dict[str, ObjectVisual] = {}
        self._recorder: Recorder = Recorder()
        self._arrivals: Arrivals = Arrivals()
        self._loading_line = ""
        self._meshes: Any = _cached_mesh_loader()
        self._lock = threading.RLock()
        self._period_s = 1.0 / display_rate_hz
        self._next_display_s = 0.0
        self._last_display_s = 0.0
        self._refresher_awake = False
        self._stall_reported = False
        self._show_frames = show_frames
        self._show_targets = show_targets
        self._error: str | None = None
        self._live = True
        self._closed = False
        try:
            self._connection = self._connect()
            self._connection.request([b"ping"])
            self._visualizer: Any = meshcat.Visualizer(window=self._connection)
            self._stage: Stage = Stage(self._visualizer)
            self._stage.frame([])
            self._plans = PlanLines(self._visualizer)
            self._link = LiveLink(self._context, self._server.zmq_url)
            self._refresher = IdleRefresher(PAUSE_S, self._refresh_if_paused)
        except BaseException:
            self.close()
            raise

    def _connect(self) -> BridgeConnection:
        from armfleet.viewer.connection import BridgeConnection

        return BridgeConnection(self._context, self._server.zmq_url, self._server.url)

    # -- properties ---------------------------------------------------------------------
    @property
    def url(self) -> str:
        """The page: ``http://127.0.0.1:<port>/static/``."""
        return self._server.url

    @property
    def port(self) -> int:
        """Web port on 127.0.0.1."""
        return self._server.web_port

    @property
    def zmq_port(self) -> int:
        """Command port of the server on 127.0.0.1."""
        return self._server.zmq_port

    @property
    def batches_sent(self) -> int:
        """Batches of live updates the server has acknowledged so far."""
        return 0 if self._link is None else self._link.batches_answered

    @property
    def server_pid(self) -> int:
        """Process id of the server."""
        return self._server.pid

    @property
    def error(self) -> str | None:
        """Why the viewer stopped, or None while it works."""
        return self._error

    @property
    def arms(self) -> tuple[str, ...]:
        """Names of the arms shown."""
        return tuple(self._visuals)

    @property
    def objects(self) -> tuple[str, ...]:
        """Names of the scene objects shown."""
        return tuple(self._objects)

    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def browsers(self) -> BrowserCount:
        """The pages open now, and those that show every mesh sent so far.

        Raises:
            ViewerError: the viewer is not running, or its server does not answer.
        """
        if not self._live or self._connection is None:
            raise ViewerError(f"the viewer is not running ({self._error or 'closed'})")
        with self._lock:  # one thread at a time on the connection
            reply = self._connection.request([b"browsers"])
        try:
            return BrowserCount(int(reply[1]), int(reply[2]))
        except (IndexError, ValueError):
            raise ViewerError(f"viewer server: unexpected answer {reply!r}") from None

    @property
    def loading_line(self) -> str:
        """The page's loading line now; empty once no awaited arm is missing."""
        return self._loading_line

    # -- arms ---------------------------------------------------------------------------
    def expect_arms(self, positions: Mapping[str, Sequence[float]]) -> None:
        """Frame the arms that are about to come, before any of their meshes is sent.

        The page then shows them all from its first frame, and a loading line until
        each of them is shown. Arms already shown keep their place in the framing.

        Args:
            positions: arm name -> where its base will stand (x, y, z) [m]; replaces
                the arms expected before.

        Raises:
            ViewerError: ``positions`` is not names with three finite numbers each.
        """
        with self._lock:
            self._arrivals.await_arms(positions)
            if not self._live:
                return
            try:
                self._frame_camera()
                self._show_loading()
            except ViewerError as exc:
                self._fail(str(exc))

    def add_arm(self, arm: Arm) -> None:
        """Load ``arm``'s meshes under ``/meshcat/armfleet/<name>`` and follow it.

        The camera frames the arm where it stands before its meshes are sent, and
        the page's loading line names it while they are on their way.
        Never raises for viewer trouble: the arm is then simply not shown.
        """
        if not self._live:
            return
        from armfleet.viewer.arm_visual import ArmVisual, arm_bounds

        try:
            with self._lock:
                try:
                    self._arrivals.arriving(arm.name, arm_bounds(arm))
                    self._frame_camera()
                    self._show_loading()
                    visual = ArmVisual(
                        arm, self._visualizer, self._show_frames, self._show_targets, self._meshes
                    )
                finally:
                    self._arrivals.arrived(arm.name)
                self._visuals[arm.name] = visual
                self._recorder.add(arm.name)
                if self._plans is not None:
                    self._plans.follow(arm)  # its planned motions, drawn while they run
                self._frame_camera()
                self._send_poses()  # at once: the simulation may not step again
                self._show_loading()  # after the meshes: the page has them when it goes
        except ViewerError as exc:
            self._fail(str(exc))
        except (RuntimeError, ValueError, OSError) as exc:  # Pinocchio/MeshCat loading
            logger.warning("viewer: cannot show %s: %s", arm.name, exc)
            self._update_loading()

    def remove_arm(self, name: str) -> None:
        """Remove arm ``name`` from the scene (and from the replay)."""
        with self._lock:
            visual = self._visuals.pop(name, None)
            self._recorder.remove(name)
            self._arrivals.arrived(name)  # awaited no more
            if self._plans is not None:
                self._plans.forget(name)  # its line goes with its node, below
            if visual is None:
                self._update_loading()
                return
            visual.close()
            if not self._live or self._link is None:
                return
            try:
                # Updates of the arm still on their way must not come after the delete.
                self._link.discard(visual.node)
                self._link.wait(STALL_TIMEOUT_S)
                self._visualizer[f"armfleet/{name}"].delete()
                self._frame_camera()
            except ViewerError as exc:
                self._fail(str(exc))

    # -- objects ------------------------------------------------------------------------
    def add_object(self, obj: WorldObject) -> None:
        """Draw ``obj`` under ``/meshcat/objects/<name>`` and follow it.

        Never raises for viewer trouble: the object is then simply not shown.
        """
        if not self._live:
            return
        from armfleet.viewer.object_visual import ObjectVisual

        try:
            with self._lock:
                self._objects[obj.name] = ObjectVisual(obj, self._visualizer)
                self._recorder.add(obj.name)
                self._frame_camera()
        except ViewerError as exc:
            self._fail(str(exc))
        except (RuntimeError, ValueError, OSError) as exc:  # a mesh file MeshCat cannot take
            logger.warning("viewer: cannot show %s: %s", obj.name, exc)

    def remove_object(self, name: str) -> None:
        """Remove object ``name`` from the scene (and from the replay)."""
        with self._lock:
            visual = self._objects.pop(name, None)
            self._recorder.remove(name)
            if visual is None or not self._live or self._link is None:
                return
            try:
                self._link.discard(visual.node)
                self._link.wait(STALL_TIMEOUT_S)
                self._visualizer[f"objects/{name}"].delete()
            except ViewerError as exc:
                self._fail(str(exc))

    def show_frames(self, visible: bool = True) -> None:
        """Show or hide every arm's ``base_link`` and ``tool0`` frames."""
        visible = flag(visible, "visible")
        self._show_frames = visible
        self._set_group_visible("landmarks", visible)

    def show_targets(self, visible: bool = True) -> None:
        """Show or hide the markers at ``tool0`` of the arms' motion targets."""
        visible = flag(visible, "visible")
        self._show_targets = visible
        self._set_group_visible("targets", visible)

    def _set_group_visible(self, group: str, visible: bool) -> None:
        if not self._live:
            return
        try:
            with self._lock:
                for name in self._visuals:
                    self._visualizer[f"armfleet/{name}/{group}"].set_property("visible", visible)
        except ViewerError as exc:
            self._fail(str(exc))

    # -- live updates -------------------------------------------------------------------
    def tick(self, world: World) -> None:
        """Called after every physics step; does work only when a frame is due."""
        if not self._live:
            return
        if world.time >= self._recorder.next_time_s:
            self._record(world.time)
        plans = self._plans
        if plans is not None and plans.busy:
            self._update_plans(plans, world.time)
        if time.perf_counter() >= self._next_display_s:
            self._display()

    def refresh(self, timeout_s: float = 5.0) -> bool:
        """Send the current pose of every arm now and wait until the server has it.

        The viewer also sends the poses by itself once the simulation pauses.

        Returns:
            Whether the server got them within ``timeout_s``.
        """
        if not self._live or self._link is None:
            return False
        with self._lock:
            try:
                self._send_poses()
                return self._link.wait(timeout_s)
            except ViewerError as exc:
                self._fail(str(exc))
                return False

    @property
    def planned_motions(self) -> dict[str, PlannedMotion]:
        """The planned motions whose tool path is drawn now, by arm."""
        return {} if self._plans is None else self._plans.shown

    def _update_plans(self, plans: PlanLines, time_s: float) -> None:
        """Draw the planned motions that started and remove those that ended."""
        with self._lock:
            try:
                plans.update(time_s)
            except ViewerError as exc:
                self._fail(str(exc))

    def _record(self, time_s: float) -> None:
        positions = {name: visual.arm.body.position for name, visual in self._visuals.items()}
        for name, thing in self._objects.items():
            positions[name] = thing.object.pose
        self._recorder.record(time_s, positions)

    def _display(self) -> None:
        now = time.perf_counter()
        self._next_display_s = now + self._period_s
        with self._lock:
            self._last_display_s = now
            try:
                self._send_poses()
            except ViewerError as exc:
                self._fail(str(exc))
                return
            if not self._refresher_awake and self._refresher is not None:
                self._refresher_awake = True
                self._refresher.wake()

    def _refresh_if_paused(self) -> bool:
        """The refresher's check: once display updates stopped, send the resting poses."""
        with self._lock:
            if not self._live:
                return True
            if time.perf_counter() - self._last_display_s < PAUSE_S:
                return False
            self._refresher_awake = False
            try:
                self._send_poses()
            except ViewerError as exc:
                self._fail(str(exc))
            return True

    def _send_poses(self) -> None:
        """Offer what changed to the link (caller holds the lock); checks a stalled server."""
        assert self._link is not None
        updates: Updates = {}
        for visual in self._visuals.values():
            visual.collect(updates)
        for thing in self._objects.values():
            thing.collect(updates)
        self._link.offer(updates)
        stalled_s = self._link.stalled_s
        if stalled_s > STALL_TIMEOUT_S:
            if not self._server.running:
                raise ViewerError("the viewer server is gone")
            if not self._stall_reported:
                self._stall_reported = True
                logger.warning("viewer: no answer for %.0f s; frames are dropped", stalled_s)
        else:
            self._stall_reported = False

    def _fail(self, reason: str) -> None:
        if self._live:
            self._live = False
            self._error = reason
            logger.warning("viewer stopped: %s; the simulation goes on without it", reason)

    # -- scene --------------------------------------------------------------------------
    def _frame_camera(self) -> None:
        bounds = [visual.bounds() for visual in self._visuals.values()]
        bounds += self._arrivals.boxes(self._visuals)
        self._stage.frame(bounds + [thing.bounds() for thing in self._objects.values()])

    def _show_loading(self) -> None:
        """Send the page's loading line if it changed (caller holds the lock)."""
        line = self._arrivals.line(self._visuals)
        if line != self._loading_line and self._connection is not None:
            self._connection.request([b"status", line.encode("utf-8")])
            self._loading_line = line

    def _update_loading(self) -> None:
        """Reframe and update the loading line after an awaited arm failed or went."""
        if not self._live:
            return
        with self._lock:
            try:
                self._frame_camera()
                self._show_loading()
            except ViewerError as exc:
                self._fail(str(exc))

    def save(self, path: str | Path) -> Path:
        """Write a standalone HTML replay of the run so far (plays from ``file://``).

        The page holds the scene and a MeshCat animation with one track set
        per arm and per object shown now, at 30 frames per simulated second.

        Raises:
            ViewerError: the viewer is not running, or the file cannot be written.
        """
        from armfleet.viewer.commands import property_command
        from armfleet.viewer.recorder import Track
        from armfleet.viewer.replay import RecordedArm, RecordedObject, replay_html

        if not self._live or self._connection is None:
            raise ViewerError(f"the viewer is not running ({self._error or 'closed'})")
        target = Path(path)
        with self._lock:  # one thread at a time on the connection
            try:
                scene = self._connection.request([b"scene"], SCENE_TIMEOUT_S)[1:]
            except ViewerError as exc:
                self._fail(str(exc))
                raise
            tracks = self._recorder.tracks
            arms = [
                RecordedArm(visual, Track(tracks[name].first_frame, list(tracks[name].positions)))
                for name, visual in self._visuals.items()
            ]
            objects = [
                RecordedObject(thing, Track(tracks[name].first_frame, list(tracks[name].positions)))
                for name, thing in self._objects.items()
            ]
            hidden = [
                property_command(f"{visual.node}/targets", "visible", False)[1]
                for visual in self._visuals.values()
            ]
            html = replay_html(scene, arms, self._recorder.fps, hidden, objects)
        try:
            target.write_text(html, encoding="utf-8")
        except OSError as exc:
            raise ViewerError(f"cannot write the replay to {target}: {exc}") from exc
        return target

    # -- lifetime -----------------------------------------------------------------------
    def close(self) -> None:
        """Stop the live updates and the server process; idempotent."""
        if self._closed:
            return
        self._closed = True
        self._live = False
        try:
            if self._refresher is not None:
                self._refresher.stop()
            with self._lock:
                for visual in self._visuals.values():
                    visual.close()
                if self._plans is not None:
                    self._plans.close()
                if self._link is not None:
                    self._link.close()
            if self._connection is not None:
                self._connection.close()
            self._context.destroy(linger=0)
        finally:
            self._server.stop()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else (self._error or "running")
        return f"Viewer({self.url!r}, arms={list(self._visuals)}, {state})"


def _cached_mesh_loader() -> Any:
    """A mesh cache for Pinocchio's geometry builder, or None without coal."""
    try:
        import coal
    except ImportError:
        return None
    return coal.CachedMeshLoader()
