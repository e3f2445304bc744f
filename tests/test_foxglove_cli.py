"""``--foxglove [PORT]`` and ``--foxglove-bind`` on the command line: the address line, the
warning for other machines, and one-line refusals (exit 2, no traceback)."""

from __future__ import annotations

import re
import socket
from collections.abc import Iterator
from pathlib import Path

import pytest

from armfleet.cli.main import main
from tests.remote_world import WorldProcess, cli

ADDRESS_LINE = re.compile(r"^foxglove: ws://127\.0\.0\.1:(\d+)$")


def fails(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    """Run ``armfleet ARGV`` in this process; return its one error line."""
    with pytest.raises(SystemExit) as exit_info:
        main(list(argv))
    assert exit_info.value.code == 2
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("armfleet: error: "), err
    assert "Traceback" not in err and out == ""
    return lines[0]


@pytest.fixture
def taken_port() -> Iterator[int]:
    with socket.socket() as listening:
        listening.bind(("127.0.0.1", 0))
        listening.listen()
        yield int(listening.getsockname()[1])


def test_spawn_with_foxglove_prints_its_address_in_one_line(tmp_path: Path) -> None:
    run = cli(
        tmp_path, "spawn", "bob", "--at", "0,0", "--foxglove", "0", "--no-viewer",
        "--duration", "0.2", "--fast",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    lines = [line for line in run.stdout.splitlines() if line.startswith("foxglove")]
    assert len(lines) == 1 and ADDRESS_LINE.match(lines[0]), run.stdout
    assert int(ADDRESS_LINE.match(lines[0]).group(1)) > 0  # type: ignore[union-attr]
    assert "warning" not in run.stderr


def test_a_running_world_serves_foxglove_and_shuts_down_cleanly(tmp_path: Path) -> None:
    """The world's process serves a real client until SIGTERM, then exits 0."""
    from tests.test_foxglove import FoxgloveClient

    with WorldProcess(tmp_path, "bob", "--at", "0,0", "--no-viewer", "--foxglove", "0") as world:
        line = next(line for line in world.stdout if line.startswith("foxglove: "))
        client = FoxgloveClient.open(line.split(" ", 1)[1])
        assert "/bob/robot_description" in client.channels and "/move" in client.services
        client.subscribe("/bob/joint_states")
        client.wait_for(lambda: len(client.messages["/bob/joint_states"]) > 10)
        ok, urdf = client.fetch("package://armfleet/robots/bob.urdf")
        assert ok and b"bob_panda_link7" in urdf
        client.close()
        # A spawn that would join this world cannot set up its Foxglove server.
        joining = cli(tmp_path, "spawn", "carol", "--at", "2,0", "--foxglove")
        assert joining.returncode == 2
        assert "--foxglove set options of a new world, but a world is running" in joining.stderr
        assert world.stop() == 0
    assert not any("Traceback" in line for line in world.stderr)


def test_a_bind_other_than_loopback_prints_the_warning(tmp_path: Path) -> None:
    run = cli(
        tmp_path, "spawn", "bob", "--at", "0,0", "--foxglove", "0", "--foxglove-bind",
        "0.0.0.0", "--no-viewer", "--duration", "0.1", "--fast", "--quiet",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    warnings = [line for line in run.stderr.splitlines() if "warning" in line]
    assert len(warnings) == 1
    assert re.match(
        r"^armfleet: warning: the Foxglove server listens on ws://0\.0\.0\.0:\d+: anyone who "
        r"can reach this machine there can command its arms$",
        warnings[0],
    )


def test_a_bad_port_from_a_real_process_is_one_line_and_exit_2(tmp_path: Path) -> None:
    run = cli(tmp_path, "spawn", "bob", "--at", "0,0", "--foxglove", "70000")
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr.splitlines() == [
        "armfleet: error: argument --foxglove: '70000' is invalid; give a TCP port (0: a free "
        "one), an integer in 0..65535 (see 'armfleet spawn --help')"
    ]


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (("--foxglove", "-1"), "argument --foxglove: '-1' is invalid"),
        (("--foxglove", "http"), "argument --foxglove: 'http' is not an integer"),
        (("--foxglove", "nan"), "argument --foxglove: 'nan'"),
        (
            ("--foxglove", "0", "--foxglove-bind", "nohost"),
            "--foxglove-bind 'nohost' is not an IP address; give one such as 127.0.0.1",
        ),
        (("--foxglove", "0", "--foxglove-bind", "1.2.3.4.5"), "is not an IP address"),
        (("--foxglove-bind", "0.0.0.0"), "--foxglove-bind goes with --foxglove [PORT]"),
        (("--foxglove-rate", "30"), "--foxglove-rate goes with --foxglove [PORT]"),
        (("--foxglove", "0", "--foxglove-rate", "0"), "argument --foxglove-rate: '0' is invalid"),
        (("--foxglove", "0", "--foxglove-rate", "inf"), "argument --foxglove-rate: 'inf'"),
        (
            ("--foxglove", "7000", "--api-port", "7000"),
            "--foxglove 7000 is also another server's port; give two ports",
        ),
    ],
)
def test_bad_foxglove_options_are_refused_in_one_line(
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    argv: tuple[str, ...],
    expected: str,
) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))  # no running world to join
    line = fails(capsys, "spawn", "bob", "--at", "0,0", "--no-viewer", *argv)
    assert expected in line, line


def test_a_taken_port_is_refused_before_any_arm_comes_up(
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    taken_port: int,
) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    line = fails(capsys, "launch", "bob_and_toby", "--no-viewer", "--foxglove", str(taken_port))
    assert f"--foxglove {taken_port}: cannot listen on 127.0.0.1:{taken_port}" in line
