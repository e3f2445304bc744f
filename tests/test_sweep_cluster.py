"""Joining a running Ray cluster by address: a real head node (``ray start --head``, on the
loopback interface, in a folder of its own), joined through its GCS address. The runs
happen in the cluster's workers, not in the sweep's.

Ray Client (``ray://``) was checked by hand against the same head (docs/sweeps.md); it is
not run here: its per-client server takes 20-40 s to start on 2 busy cores and failed to
start once in five tries ("Starting Ray client server failed"), which is Ray's, not armfleet's.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pyarrow.parquet as pq
import pytest

ARMFLEET = [sys.executable, "-m", "armfleet.cli.main"]
RAY = Path(sys.executable).with_name("ray")


def free_ports(count: int) -> list[int]:
    """``count`` distinct free ports: every probe stays bound until all are chosen, since
    the kernel may hand a just-closed port out again (CI once got one port twice)."""
    with contextlib.ExitStack() as stack:
        probes = [stack.enter_context(socket.socket()) for _ in range(count)]
        for probe in probes:
            probe.bind(("127.0.0.1", 0))
        return [int(probe.getsockname()[1]) for probe in probes]


@pytest.fixture(scope="module")
def head() -> Iterator[tuple[int, int, Path]]:
    """A one-machine cluster: (GCS port, Ray Client port, its folder)."""
    # A short folder: Ray's Unix sockets live in it, and their paths may not exceed 107
    # bytes (a pytest-xdist worker's tmp_path is too deep).
    folder = Path(tempfile.mkdtemp(prefix="ray-", dir="/tmp"))
    # Every port the head opens is free and its own: a private local Ray instance of
    # another test (on the other pytest worker) holds Ray's default agent ports.
    options = (
        "node-manager-port", "object-manager-port", "dashboard-agent-listen-port",
        "dashboard-agent-grpc-port", "runtime-env-agent-port", "metrics-export-port",
    )  # fmt: skip
    gcs, client, *chosen = free_ports(2 + len(options))
    ports = [f"--{option}={port}" for option, port in zip(options, chosen, strict=True)]
    env = {**os.environ, "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}  # loopback only
    log = (folder / "ray-start.log").open("w")
    process = subprocess.Popen(
        [str(RAY), "start", "--head", "--block", f"--port={gcs}",
         f"--ray-client-server-port={client}", *ports, "--num-cpus=2",
         "--include-dashboard=false", "--disable-usage-stats", f"--temp-dir={folder}"],
        env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:  # until its client port answers
            try:
                socket.create_connection(("127.0.0.1", client), timeout=1).close()
                break
            except OSError:
                if process.poll() is not None:
                    tail = (folder / "ray-start.log").read_text()[-2000:]
                    pytest.fail(f"ray start --head ended:\n{tail}")
                time.sleep(0.3)
        else:
            pytest.fail("the head node did not start within 60 s")
        yield gcs, client, folder
    finally:
        with contextlib.suppress(ProcessLookupError):  # it may have ended by itself
            os.killpg(process.pid, signal.SIGINT)  # --block stops the node on Ctrl-C
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
        log.close()
        shutil.rmtree(folder, ignore_errors=True)


def test_a_sweep_joins_a_cluster_by_address(head: tuple[int, int, Path], tmp_path: Path) -> None:
    gcs, _, folder = head
    address = f"127.0.0.1:{gcs}"
    output = tmp_path / "r.parquet"
    env = {**os.environ, "RAY_AUTH_MODE": "token"}  # Ray asks it of an explicit address
    result = subprocess.run(
        [*ARMFLEET, "sweep", "reach", "--runs", "4", "--address", address, "-o", str(output),
         "--quiet"],
        capture_output=True, text=True, timeout=240, env=env,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    table = pq.read_table(output).to_pylist()
    assert sorted(row["seed"] for row in table) == [0, 1, 2, 3]
    assert all(row["ok"] for row in table)
    for pid in {row["pid"] for row in table}:  # the cluster's raylet started the workers
        assert list(folder.glob(f"session_*/logs/worker-*-{pid}.out")), pid
