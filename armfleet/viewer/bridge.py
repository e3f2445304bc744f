"""The viewer's server process: the MeshCat page and its websocket, on 127.0.0.1 only.

MeshCat's stock server listens on every interface; this one binds its web
port and its ZMQ port to the loopback address, on free ports unless a web
port is given. :class:`armfleet.viewer.server.ViewerServer` runs this file as
a script (``runpy``), so it imports only tornado, pyzmq and umsgpack, never
armfleet. It prints one JSON line on stdout, ``{"web_port": ..., "zmq_port": ...}``
or ``{"error": "..."}``, then serves until its parent process is gone or it is
terminated.

ZMQ protocol (a REP socket; every request gets one reply):

- ``[type, path, data]``: one MeshCat command (``set_object``, ``set_transform``,
  ``set_property``, ``delete``, ``set_animation``); kept in the scene tree and
  sent to every browser. Reply ``ok``.
- ``[b"batch", index, data]``: live updates (``set_transform``, ``set_property``),
  many commands in one request: ``data`` is their msgpack bytes end to end,
  ``index`` is ``type NUL path NUL length`` per command, NUL-separated. They
  reach a page as one websocket message, a msgpack array that armfleet's page
  unrolls. A page whose socket is still busy with earlier data skips them and
  later gets the latest state of each node it missed: a slow browser sees
  fewer frames, and nothing waits for it.
- ``[b"scene"]``: reply ``[b"scene", command, ...]``, the commands that rebuild
  the current scene, in order.
- ``[b"status", text]``: the loading line the page shows over the scene (UTF-8; empty:
  none). A page gets it after every command sent before it, so it goes when what it
  announces is in the page: a page that opens later gets the scene, then the line.
  Reply ``ok``.
- ``[b"browsers"]``: reply ``[b"browsers", connected, shown]``, two decimal counts: the
  pages connected, and those among them that reported the scene shown (a page answers
  :data:`SHOWN_MESSAGE` and the line's serial once it handled an empty loading line).
- ``[b"ping"]``: reply ``ok``.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import os
import signal
import socket
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import tornado.httpserver
import tornado.ioloop
import tornado.netutil
import tornado.web
import tornado.websocket
import umsgpack
import zmq
from zmq.eventloop.zmqstream import ZMQStream

LOOPBACK = "127.0.0.1"
COMMANDS = frozenset(
    {b"set_object", b"set_transform", b"set_property", b"delete", b"set_animation"}
)
#: Commands a batch may carry: they only change the state of existing nodes.
LIVE_COMMANDS = frozenset({b"set_transform", b"set_property"})
PARENT_CHECK_MS = 250
#: armfleet's page (MeshCat's viewer plus a mesh cache); MeshCat's script comes from its package.
OWN_PAGE_FOLDER = Path(__file__).with_name("static")

#: Field of a mesh-file object naming its mesh; the page parses each named mesh once.
MESH_TAG = "armfleet_mesh"
#: Command type of the loading line (armfleet's page handles it; MeshCat never sees it).
STATUS_COMMAND = "armfleet_status"
#: What a page sends, with the line's serial, once it handled an empty loading line.
SHOWN_MESSAGE = "armfleet:shown:"

NodePath = tuple[str, ...]


def msgpack_array(items: Sequence[bytes]) -> bytes:
    """A msgpack array of already-packed ``items``."""
    count = len(items)
    if count < 16:
        head = bytes([0x90 | count])
    elif count < 2**16:
        head = b"\xdc" + count.to_bytes(2, "big")
    else:
        head = b"\xdd" + count.to_bytes(4, "big")
    return head + b"".join(items)


class SharedMesh(NamedTuple):
    """A ``set_object`` of a mesh file, sendable without the file to a page that has it.

    Attributes:
        digest: names the mesh (file text, transform, materials).
        full: the command, tagged with ``digest``.
        reference: the same command without the file text.
    """

    digest: str
    full: bytes
    reference: bytes


def share_mesh(data: bytes) -> SharedMesh | None:
    """A :class:`SharedMesh` for a ``set_object`` of a mesh file; None for other commands."""
    if b"_meshfile_object" not in data:
        return None
    command = umsgpack.unpackb(data)
    wrapper = command.get("object") if isinstance(command, dict) else None
    if not isinstance(wrapper, dict):
        return None
    inner = wrapper.get("object")
    if not isinstance(inner, dict) or inner.get("type") != "_meshfile_object":
        return None
    text = inner.get("data")
    if not isinstance(text, str | bytes):
        return None
    materials = [
        {key: value for key, value in material.items() if key != "uuid"}
        for material in wrapper.get("materials", [])
        if isinstance(material, dict)
    ]
    identity = [inner.get("format"), inner.get("matrix"), inner.get("resources"), materials, text]
    digest = hashlib.sha256(umsgpack.packb(identity)).hexdigest()[:32]
    inner[MESH_TAG] = digest
    full = umsgpack.packb(command)
    inner["data"] = text[:0]
    return SharedMesh(digest, full, umsgpack.packb(command))


#: What a node holds and a browser is sent.
Message = bytes | SharedMesh


def status_command(text: str, serial: int) -> bytes:
    """The page's command showing ``text`` as its loading line (empty: hide it)."""
    packed: bytes = umsgpack.packb({"type": STATUS_COMMAND, "text": text, "serial": serial})
    return packed


def split_path(path: bytes) -> NodePath:
    """``b"/meshcat/armfleet/bob"`` -> ``("meshcat", "armfleet", "bob")``."""
    return tuple(part for part in path.decode("utf-8").split("/") if part)


class SceneNode:
    """One node of the scene as the server keeps it: the latest command of each kind."""

    __slots__ = ("animation", "children", "object", "properties", "transform")

    def __init__(self) -> None:
        self.children: dict[str, SceneNode] = {}
        self.object: Message | None = None
        self.transform: bytes | None = None
        self.properties: dict[str, bytes] = {}
        self.animation: bytes | None = None

    def find(self, path: NodePath) -> SceneNode:
        """The node at ``path``, created (with its parents) if missing."""
        node = self
        for name in path:
            node = node.children.setdefault(name, SceneNode())
        return node

    def get(self, path: NodePath) -> SceneNode | None:
        """The node at ``path``, or None; creates nothing."""
        node: SceneNode | None = self
        for name in path:
            if node is None:
                return None
            node = node.children.get(name)
        return node

    def delete(self, path: NodePath) -> None:
        if not path:
            self.children.clear()
            self.object = self.transform = self.animation = None
            self.properties.clear()
            return
        parent = self.get(path[:-1])
        if parent is not None:
            parent.children.pop(path[-1], None)

    def state(self) -> Iterator[Message]:
        """This node's own commands: object, properties, transform, animation."""
        if self.object is not None:
            yield self.object
        yield from self.properties.values()
        if self.transform is not None:
            yield self.transform
        if self.animation is not None:
            yield self.animation

    def live_state(self) -> Iterator[bytes]:
        """What live updates set: properties and transform (objects are never skipped)."""
        yield from self.properties.values()
        if self.transform is not None:
            yield self.transform

    def commands(self) -> Iterator[Message]:
        """Every command of this subtree, parents before children."""
        yield from self.state()
        for child in self.children.values():
            yield from child.commands()


class BrowserSocket(tornado.websocket.WebSocketHandler):
    """The websocket of one browser tab."""

    def initialize(self, bridge: Bridge) -> None:
        self.bridge = bridge
        self._pending: Any = None  # the Future of the last write
        self._stale: set[NodePath] = set()
        self._meshes: set[str] = set()  # digests of the meshes this page has
        #: The page reported the scene shown (and no loading line came since).
        self.shown = False

    def prepare(self) -> None:
        check_host(self)

    def open(self, *args: str, **kwargs: str) -> None:
        self.bridge.browsers.add(self)
        self.write_all([*self.bridge.tree.commands(), self.bridge.status])

    def on_close(self) -> None:
        self.bridge.browsers.discard(self)

    def on_message(self, message: str | bytes) -> None:
        """The page's report that it shows the scene; image captures are ignored."""
        # A report on an earlier line is stale: a new line came since.
        if message == f"{SHOWN_MESSAGE}{self.bridge.status_serial}":
            self.shown = True

    @property
    def busy(self) -> bool:
        return self._pending is not None and not self._pending.done()

    def write_all(self, messages: Sequence[Message]) -> None:
        future = None
        try:
            for message in messages:
                if isinstance(message, SharedMesh):
                    known = message.digest in self._meshes
                    self._meshes.add(message.digest)
                    message = message.reference if known else message.full
                future = self.write_message(message, binary=True)
        except tornado.websocket.WebSocketClosedError:
            return
        if future is not None:
            self._pending = future
            future.add_done_callback(lambda _: self._catch_up())

    def write_latest(self, paths: Sequence[NodePath], commands: Sequence[bytes]) -> None:
        """Send live updates as one message, or note their nodes if the socket is busy."""
        if self.busy:
            self._stale.update(paths)
        elif commands:
            self.write_all([msgpack_array(commands)])

    def _catch_up(self) -> None:
        if not self._stale or self.busy:
            return
        stale, self._stale = self._stale, set()
        commands: list[bytes] = []
        for path in stale:
            node = self.bridge.tree.get(path)
            if node is not None:
                commands.extend(node.live_state())
        self.write_latest(list(stale), commands)


class PageHandler(tornado.web.StaticFileHandler):
    """The page and its scripts, for loopback host names only."""

    def prepare(self) -> None:
        check_host(self)


def check_host(handler: tornado.web.RequestHandler) -> None:
    """Refuse requests for a host name other than the server's own (DNS rebinding)."""
    if handler.request.host not in handler.settings["loopback_hosts"]:
        raise tornado.web.HTTPError(403)


class Bridge:
    """Web server, websockets and ZMQ socket of the viewer, all on 127.0.0.1.

    Args:
        web_port: port of the page; 0 for a free one.
        parent_pid: exit when this process is gone (None: never check).
    """

    def __init__(self, web_port: int, parent_pid: int | None) -> None:
        self.tree = SceneNode()
        self.browsers: set[BrowserSocket] = set()
        #: The loading line's command, as pages get it, and its serial.
        self.status_serial = 0
        self.status: bytes = status_command("", self.status_serial)
        self._live_nodes: dict[bytes, tuple[NodePath, SceneNode]] = {}
        self._parent_pid = parent_pid
        sockets = tornado.netutil.bind_sockets(web_port, address=LOOPBACK, family=socket.AF_INET)
        self.web_port: int = sockets[0].getsockname()[1]
        self._context = zmq.Context()
        self._socket = self._context.socket(zmq.REP)
        self._socket.setsockopt(zmq.LINGER, 0)
        self.zmq_port: int = self._socket.bind_to_random_port(f"tcp://{LOOPBACK}")
        self._stream = ZMQStream(self._socket)
        self._stream.on_recv(self._on_request)
        own = {"path": str(OWN_PAGE_FOLDER), "default_filename": "index.html"}
        meshcat = {"path": str(meshcat_page_folder())}
        app = tornado.web.Application(
            [
                (r"/static/((?:index\.html)?|armfleet-[a-z-]+\.js)", PageHandler, own),
                (r"/static/(.*)", PageHandler, meshcat),
                (r"/", BrowserSocket, {"bridge": self}),
            ],
            loopback_hosts={f"{LOOPBACK}:{self.web_port}", f"localhost:{self.web_port}"},
        )
        self._http = tornado.httpserver.HTTPServer(app)
        self._http.add_sockets(sockets)

    def serve(self) -> None:
        if self._parent_pid is not None:
            tornado.ioloop.PeriodicCallback(self._check_parent, PARENT_CHECK_MS).start()
        tornado.ioloop.IOLoop.current().start()

    def _check_parent(self) -> None:
        if os.getppid() != self._parent_pid:
            tornado.ioloop.IOLoop.current().stop()

    # -- ZMQ requests ------------------------------------------------------------------
    def _on_request(self, frames: list[bytes]) -> None:
        try:
            reply = self._answer(frames)
        except Exception as exc:  # a malformed command must not leave the client waiting
            reply = [f"error: {type(exc).__name__}: {exc}".encode()[:200]]
        self._socket.send_multipart(reply)

    def _answer(self, frames: list[bytes]) -> list[bytes]:
        kind = frames[0]
        if kind == b"batch":
            self._on_batch(frames[1:])
            return [b"ok"]
        if kind == b"scene":
            commands = self.tree.commands()
            return [b"scene", *(c.full if isinstance(c, SharedMesh) else c for c in commands)]
        if kind == b"ping":
            return [b"ok"]
        if kind == b"status" and len(frames) == 2:
            self._on_status(frames[1].decode("utf-8"))
            return [b"ok"]
        if kind == b"browsers":
            shown = sum(browser.shown for browser in self.browsers)
            return [b"browsers", str(len(self.browsers)).encode(), str(shown).encode()]
        if kind in COMMANDS and len(frames) == 3:
            message = self._apply(kind, split_path(frames[1]), frames[2])
            for browser in list(self.browsers):
                browser.write_all([message])
            return [b"ok"]
        return [b"error: unknown request " + kind[:40]]

    def _on_status(self, text: str) -> None:
        self.status_serial += 1
        self.status = status_command(text, self.status_serial)
        for browser in list(self.browsers):
            if text:
                browser.shown = False
            browser.write_all([self.status])

    def _on_batch(self, frames: list[bytes]) -> None:
        if len(frames) != 2:
            raise ValueError("a batch is [index, data]")
        index, data = frames
        fields = index.split(b"\0") if index else []
        if len(fields) % 3:
            raise ValueError("a batch index holds type, path and length per command")
        paths: list[NodePath] = []
        commands: list[bytes] = []
        view = memoryview(data)
        offset = 0
        for i in range(0, len(fields), 3):
            kind, path, size = fields[i], fields[i + 1], int(fields[i + 2])
            if kind not in LIVE_COMMANDS:
                raise ValueError(f"a batch cannot carry {kind.decode(errors='replace')}")
            command = bytes(view[offset : offset + size])
            offset += size
            node_path, node = self._live_node(path)
            if kind == b"set_transform":
                node.transform = command
            else:
                node.properties[str(umsgpack.unpackb(command).get("property"))] = command
            paths.append(node_path)
            commands.append(command)
        for browser in list(self.browsers):
            browser.write_latest(paths, commands)

    def _live_node(self, path: bytes) -> tuple[NodePath, SceneNode]:
        """The node a live update names, remembered: the same nodes come again and again."""
        known = self._live_nodes.get(path)
        if known is None:
            node_path = split_path(path)
            known = self._live_nodes[path] = (node_path, self.tree.find(node_path))
        return known

    def _apply(self, kind: bytes, path: NodePath, data: bytes) -> Message:
        """Keep the command in the tree; returns what to send to browsers."""
        if kind == b"delete":
            self.tree.delete(path)
            self._live_nodes.clear()
            return data
        node = self.tree.find(path)
        if kind == b"set_object":
            node.object = share_mesh(data) or data
            return node.object
        if kind == b"set_transform":
            node.transform = data
        elif kind == b"set_property":
            node.properties[str(umsgpack.unpackb(data).get("property"))] = data
        else:
            node.animation = data
        return data


def meshcat_page_folder() -> Path:
    """MeshCat's ``viewer/dist`` folder (index.html, main.min.js), found without importing it."""
    spec = importlib.util.find_spec("meshcat")
    if spec is None or spec.origin is None:
        raise FileNotFoundError("the meshcat package is not installed")
    return Path(spec.origin).parent / "viewer" / "dist"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="armfleet viewer server (loopback only)")
    parser.add_argument("--web-port", type=int, default=0)
    parser.add_argument("--parent-pid", type=int, default=None)
    args = parser.parse_args(argv)
    # Ctrl-C reaches the whole process group: the parent decides when this ends.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        bridge = Bridge(args.web_port, args.parent_pid)
    except (OSError, zmq.ZMQError) as exc:
        where = f"{LOOPBACK}:{args.web_port}" if args.web_port else LOOPBACK
        print(json.dumps({"error": f"cannot listen on {where}: {exc}"}), flush=True)
        return 1
    print(json.dumps({"web_port": bridge.web_port, "zmq_port": bridge.zmq_port}), flush=True)
    # Nothing else goes to the parent's pipe.
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    bridge.serve()
    return 0


if __name__ == "__main__":
    sys.exit(main())
