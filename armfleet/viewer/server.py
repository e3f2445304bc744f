"""The viewer's server process, as seen from the simulation: start, address, stop.

The server (:mod:`armfleet.viewer.bridge`) is a child process bound to
127.0.0.1. It dies with its parent in every case: :meth:`ViewerServer.stop`
ends it (called by ``Viewer.close``, and by ``atexit`` if nobody did), and the
child itself exits when it sees its parent is gone (killed, crashed).
"""

from __future__ import annotations

import atexit
import json
import os
import select
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from armfleet.viewer.errors import ViewerError

LOOPBACK = "127.0.0.1"
#: Runs bridge.py as a script: the package (pybullet, pinocchio) is not imported
#: and the current folder is not put on sys.path.
_BOOTSTRAP = (
    "import sys; del sys.path[0]; script = sys.argv.pop(1); sys.argv[0] = script; "
    "import runpy; runpy.run_path(script, run_name='__main__')"
)
START_TIMEOUT_S = 15.0
STOP_TIMEOUT_S = 3.0


class ViewerServer:
    """A running viewer server process.

    Use :meth:`start`; its ports are known once it runs.

    Attributes:
        web_port: port of the page on 127.0.0.1.
        zmq_port: port of the command socket on 127.0.0.1.
    """

    def __init__(self, process: subprocess.Popen[bytes], web_port: int, zmq_port: int) -> None:
        self._process = process
        self.web_port = web_port
        self.zmq_port = zmq_port
        atexit.register(self.stop)

    @classmethod
    def start(cls, web_port: int | None = None, timeout_s: float = START_TIMEOUT_S) -> ViewerServer:
        """Start the server and wait until it listens.

        Args:
            web_port: port of the page; a free one if None.
            timeout_s: how long to wait for it to listen [s].

        Raises:
            ViewerError: it could not start (port taken, missing package, timeout).
        """
        if web_port is not None and not 0 < web_port < 65536:
            raise ViewerError(f"viewer port {web_port} is invalid; choose 1-65535 or none")
        script = Path(__file__).with_name("bridge.py")
        args = [sys.executable, "-u", "-c", _BOOTSTRAP, str(script)]
        args += ["--web-port", str(web_port or 0), "--parent-pid", str(os.getpid())]
        with tempfile.TemporaryFile() as errors:
            try:
                process = subprocess.Popen(
                    args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=errors
                )
            except OSError as exc:
                raise ViewerError(f"cannot run the viewer server: {exc}") from exc
            try:
                reply = _read_handshake(process, timeout_s)
            except ViewerError as exc:
                _end(process)
                errors.seek(0)
                detail = errors.read().decode(errors="replace").strip().splitlines()
                raise ViewerError(f"{exc}{': ' + detail[-1] if detail else ''}") from None
        if "error" in reply:
            _end(process)
            raise ViewerError(f"viewer server: {reply['error']}")
        return cls(process, int(reply["web_port"]), int(reply["zmq_port"]))

    @property
    def pid(self) -> int:
        return self._process.pid

    @property
    def url(self) -> str:
        """The page: ``http://127.0.0.1:<port>/static/``."""
        return f"http://{LOOPBACK}:{self.web_port}/static/"

    @property
    def zmq_url(self) -> str:
        return f"tcp://{LOOPBACK}:{self.zmq_port}"

    @property
    def running(self) -> bool:
        return self._process.poll() is None

    def stop(self) -> None:
        """End the process and wait for it; idempotent."""
        atexit.unregister(self.stop)
        _end(self._process)


def _read_handshake(process: subprocess.Popen[bytes], timeout_s: float) -> dict[str, Any]:
    assert process.stdout is not None  # Popen(stdout=PIPE)
    deadline = time.monotonic() + timeout_s
    try:
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise ViewerError(f"the viewer server did not start within {timeout_s:g} s")
            ready, _, _ = select.select([process.stdout], [], [], remaining)
            if ready:
                line = process.stdout.readline()
                if not line:
                    code = process.wait()
                    raise ViewerError(f"the viewer server exited with code {code} before starting")
                try:
                    reply = json.loads(line)
                except ValueError:
                    continue
                if isinstance(reply, dict):
                    return reply
    finally:
        process.stdout.close()


def _end(process: subprocess.Popen[bytes]) -> None:
    if process.poll() is not None:
        return
    process.terminate()
    try:
        process.wait(STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
