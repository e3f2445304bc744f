"""A world served to ROS 2 keeps to this machine (issue 29): traced with strace while a
node talks to it, every socket the world's process binds is on the loopback, and every
address it connects or sends to is a loopback one (no multicast, no other interface)."""

from __future__ import annotations

import contextlib
import ipaddress
import os
import re
import shutil
import signal
import subprocess
from pathlib import Path

import pytest

from tests.remote_world import ARMFLEET, registered_pid, runtime_env
from tests.ros_world import ros_domain_id, ros_node

#: Address fields strace prints for IPv4 and IPv6 socket addresses.
_ADDRESS = re.compile(r'inet_addr\("([0-9.]+)"\)|inet_pton\(AF_INET6, "([0-9a-fA-F:.]+)"')
_CALL = re.compile(r"^\d+\s+(\w+)\(")


def _addresses(trace: str) -> dict[str, set[str]]:
    """Per system call (bind, connect, sendto, sendmsg, ...), the IP addresses it named
    (failed calls included: an attempt counts)."""
    found: dict[str, set[str]] = {}
    for line in trace.splitlines():
        call = _CALL.match(line)
        if call is None:
            continue
        for v4, v6 in _ADDRESS.findall(line):
            found.setdefault(call.group(1), set()).add(v4 or v6)
    return found


@pytest.mark.skipif(
    shutil.which("strace") is None, reason="needs strace (scripts/test.sh installs it)"
)
def test_every_socket_and_destination_of_the_world_is_on_the_loopback(tmp_path: Path) -> None:
    domain = ros_domain_id()
    trace = tmp_path / "trace.txt"
    world = subprocess.Popen(
        [
            "strace", "-f", "--seccomp-bpf", "-qq", "-o", str(trace),
            "-e", "trace=bind,connect,sendto,sendmsg,sendmmsg",
            *ARMFLEET, "spawn", "bob", "--at", "0,0", "--no-viewer", "--realtime",
            "--ros", "--ros-domain", str(domain), "--duration", "30",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=runtime_env(tmp_path),
    )  # fmt: skip
    try:
        seen = ros_node(domain, "watch", {"arm": "bob", "seconds": 1.0})
        assert seen["joint_state_count"] > 10  # traffic really flowed
    finally:
        # The world, not strace (which would leave it running to its --duration).
        with contextlib.suppress(FileNotFoundError, ProcessLookupError):
            os.kill(registered_pid(tmp_path), signal.SIGTERM)
        try:
            world.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            world.kill()
            world.communicate()
    found = _addresses(trace.read_text())
    assert found.get("bind"), "the trace shows no bound socket: strace saw nothing"
    for call, addresses in found.items():
        for address in addresses:
            assert ipaddress.ip_address(address).is_loopback, (call, address, found)
