"""Client commands' mistakes: each is one line on stderr and exit code 2, no traceback."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import armfleet
from armfleet.cli.main import main
from armfleet.description import ModelLibrary
from tests.remote_world import WorldProcess, api_threads, cli, runtime_file

#: How an unknown-model error lists the choices: every model in description/.
AVAILABLE_MODELS = "available: " + ", ".join(ModelLibrary().names)


@pytest.fixture(scope="module")
def running(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The runtime folder of a running world with bob."""
    runtime = tmp_path_factory.mktemp("runtime")
    with WorldProcess(runtime, "bob", "--at", "0,0", "--no-viewer"):
        yield runtime


def fails(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    """Run ``armfleet ARGV`` in this process; return its one error line."""
    with pytest.raises(SystemExit) as exit_info:
        main(list(argv))
    assert exit_info.value.code == 2
    _, err = capsys.readouterr()
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("armfleet: error: "), err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["move", "zed", "--joints", "0"], "no arm named 'zed'; arms: bob"),
        (["move", "bob", "--joints", "0", "0.1", "0.2"], "got 3 target positions, expected 7"),
        (["move", "bob", "--joints", "nan", *["0"] * 6], "bob_panda_joint1 is nan"),
        (["move", "bob", "--joints", "9", *["0"] * 6], "outside its limits"),
        (["move", "bob", "--joints", "fast"], "invalid float value: 'fast'"),
        (["remove", "zed"], "no arm named 'zed'"),
        (["topic", "echo", "/zed/joint_states"], "unknown topic '/zed/joint_states'; topics:"),
        (["topic", "echo", "/bob/joint_states", "--rate", "0"], "--rate 0.0 is invalid"),
        (["topic"], "required: {list,echo}"),
        (["topic", "show"], "invalid choice: 'show'"),
        (["step"], "the world is running; pause it first"),
        (["spawn", "carol", "--at", "0.1,0"], "carol would touch bob at its start pose"),
        (["spawn", "carol", "--at", "2,0", "--model", "pand"], AVAILABLE_MODELS),
        (["spawn", "bob", "--at", "2,0"], "'bob' is already used in this world"),
        (
            ["spawn", "carol", "--at", "2,0", "--fast", "--duration", "1"],
            "--duration, --realtime/--fast set options of a new world, but a world is running",
        ),
        (["spawn", "carol", "--at", "2,0", "--new-world", "--connect", "5555"], "exclude each"),
        (["arms", "--connect", "tcp://nowhere"], "address 'tcp://nowhere' is malformed"),
        (["arms", "--timeout", "-1"], "argument --timeout: '-1' is invalid"),
    ],
    ids=lambda value: " ".join(value) if isinstance(value, list) else None,
)
def test_a_mistake_against_a_running_world_is_one_line(
    running: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    says: str,
) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(running))
    assert says in fails(capsys, *argv)
    with armfleet.connect() as client:
        assert client.info().arms == ("bob",)  # nothing half-done
        assert client.info().streams == 0  # no stream left open by the failed command
    assert not api_threads()


def test_no_world_running_or_none_answering(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    line = fails(capsys, "arms")
    assert "no running world found" in line and "--connect ADDR" in line
    address = "tcp://127.0.0.1:9"  # discard port: nothing answers there
    line = fails(capsys, "info", "--connect", address, "--timeout", "0.3")
    assert f"no answer from a world at {address} (given) within 0.3 s" in line
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], text=True, capture_output=True
    )
    path = runtime_file(tmp_path)
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps({"address": address, "pid": int(dead.stdout)}))
    assert "which has ended" in fails(capsys, "pause")


def test_a_real_process_exits_2_with_one_line(tmp_path: Path) -> None:
    result = cli(tmp_path, "move", "bob", "--joints", "0")
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.startswith("armfleet: error: no running world found")
    assert len(result.stderr.splitlines()) == 1
