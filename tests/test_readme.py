"""The README is the short path and the docs/ pages hold the rest; both stay true.

The README's two set-up commands are the real ones, its Python example runs, its CLI summary
names every subcommand and only real options, the spawn output it shows has the shape of a
real run's, and every relative link in the README and docs/ reaches a file (and heading).
Each docs page's ``python`` blocks run in order as one program.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import armfleet
from tests.remote_world import WorldProcess, cli

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
#: The topic pages issue #14 asks for, besides the index docs/README.md.
PAGES = (
    "live-api.md",
    "cli.md",
    "manipulation.md",
    "recording.md",
    "safety.md",
    "performance.md",
    "descriptions-and-specs.md",
    "design.md",
    "planning.md",
    "sweeps.md",
    "foxglove.md",
    "envs.md",
    "ros2.md",
)
#: Pages whose ``python`` blocks need more than this file gives them, and who runs them.
RUN_ELSEWHERE = {
    # Its client example needs a world running in another process.
    "live-api.md": "tests/test_remote_session.py::test_the_live_api_example_runs_as_written",
    # Each block is a script of its own (a vector env's workers import it), training shortened.
    "envs.md": "tests/test_docs_envs_snippets.py::test_the_snippet_runs_as_a_script",
    # Its node talks to a world served to ROS 2 in another process.
    "ros2.md": "tests/test_docs_ros2.py::test_the_world_command_and_the_node_work_as_written",
}
#: Longest README: the short path fits a couple of screens (it was 610 lines).
MAX_README_LINES = 150
#: How close an arm at rest holds its target [rad].
HOLD_TOLERANCE_RAD = 1e-3
ARMFLEET = (sys.executable, "-m", "armfleet.cli.main")


def code_blocks(path: Path, language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", path.read_text(), re.DOTALL | re.MULTILINE)


def section(path: Path, heading: str) -> str:
    """The text under ``## heading`` up to the next ``## ``."""
    text = path.read_text()
    start = text.index(f"\n## {heading}\n")
    end = text.find("\n## ", start + 1)
    return text[start : end if end >= 0 else len(text)]


def armfleet_help(*args: str) -> str:
    done = subprocess.run([*ARMFLEET, *args, "--help"], capture_output=True, text=True, check=True)
    return done.stdout


#: Prints ``armfleet ARGS --help`` for each ARGS given, in one process (not 20 start-ups).
HELPS = """
import contextlib, io, sys
from armfleet.cli.main import main
for command in sys.argv[1:]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
        main([*command.split(), "--help"])
    print(out.getvalue())
"""


def armfleet_helps(*commands: str) -> str:
    """The ``--help`` text of every command given (e.g. ``"move"``, ``"topic echo"``)."""
    args = [sys.executable, "-c", HELPS, *commands]
    return subprocess.run(args, capture_output=True, text=True, check=True).stdout


def subcommands() -> list[str]:
    found = re.search(r"^usage: armfleet .*?\{([a-z,-]+)\}", armfleet_help(), re.M | re.S)
    assert found is not None, "armfleet --help lists no subcommands"
    return found.group(1).split(",")


def markdown_files() -> list[Path]:
    return [README, *sorted(DOCS.glob("*.md"))]


def test_readme_is_the_short_path() -> None:
    lines = README.read_text().splitlines()
    assert len(lines) <= MAX_README_LINES
    headings = [line for line in lines if line.startswith("## ")]
    assert headings == [
        "## Set up",
        "## Python",
        "## Command line",
        "## Your own robot",
        "## Documentation",
    ]
    index = (DOCS / "README.md").read_text()
    for page in PAGES:
        assert (DOCS / page).is_file(), page
        assert f"(docs/{page})" in README.read_text(), f"the README does not link docs/{page}"
        assert f"({page})" in index, f"docs/README.md does not link {page}"


def test_python_example_runs() -> None:
    (example,) = code_blocks(README, "python")
    assert len(example.splitlines()) <= 20
    namespace: dict[str, object] = {}
    exec(compile(example, str(README), "exec"), namespace)
    world = namespace["world"]
    assert getattr(world, "closed", False)


def test_exactly_two_setup_commands_and_ci_runs_the_test_one() -> None:
    shell = re.findall(r"^```(?:bash|sh|shell|console)\n", README.read_text(), re.MULTILINE)
    commands = [block.strip() for block in code_blocks(README, "bash")]
    assert len(shell) == len(commands) == 2
    assert "armfleet spawn bob toby --at 0,0 1,0" in commands[0]
    ci = (ROOT / ".ci" / "run").read_text()
    assert commands[1] in ci
    setup = section(README, "Set up")
    assert "source .venv/bin/activate" in setup  # how armfleet gets on PATH
    assert re.search(r"took\s+\d+ s", setup), "the install time is stated"


def test_readme_says_a_spawn_joins_the_running_world_and_how_not_to() -> None:
    setup = " ".join(section(README, "Set up").split())
    assert "*joins it*" in setup
    assert "`armfleet spawn ... --new-world` starts a separate one" in setup
    assert "--new-world" in armfleet_help("spawn")


def test_cli_summary_names_every_subcommand_and_only_real_options() -> None:
    summary = code_blocks(README, "text")[2]
    assert summary.lstrip().startswith("armfleet spawn")
    words = set(re.findall(r"[a-z][a-z-]*", summary))
    existing = subcommands()
    missing = [name for name in existing if name not in words]
    assert not missing, f"subcommands missing from the README's CLI summary: {missing}"
    named = set(re.findall(r"armfleet ([a-z-]+)", summary))
    named |= set(re.findall(r"\| ([a-z][a-z-]*)", summary))
    assert named <= set(existing) | {"list", "echo"}, named - set(existing)
    helps = armfleet_helps(*existing, "topic list", "topic echo")
    assert "usage: armfleet topic echo" in helps
    options = set(re.findall(r"--[a-z][a-z-]*", summary))
    unknown = sorted(option for option in options if option not in helps)
    assert not unknown, f"options in the README's CLI summary that no command takes: {unknown}"


def test_the_spawn_output_shown_is_what_a_spawn_prints(tmp_path: Path) -> None:
    shown = code_blocks(README, "text")[0].splitlines()
    env = os.environ | {"XDG_RUNTIME_DIR": str(tmp_path), "PYTHONUNBUFFERED": "1"}
    # --duration 2.5: long enough for a status line (once a second), short for a test.
    done = subprocess.run(
        [*ARMFLEET, "spawn", "bob", "toby", "--at", "0,0", "1,0", "--duration", "2.5"],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=True,
    )
    printed = done.stdout.splitlines()
    assert shown[0].startswith("viewer: http://127.0.0.1:") and shown[0].endswith("/static/")
    assert re.fullmatch(r"viewer: http://127\.0\.0\.1:\d+/static/", printed[0]), printed
    for line in shown[1:]:
        if line == "...":
            continue
        # Numbers differ from run to run, and the status line is shortened with "...".
        prefix = re.sub(r"\d+(\.\d+)?", "#", line.split("...")[0])
        assert any(re.sub(r"\d+(\.\d+)?", "#", out).startswith(prefix) for out in printed), (
            line,
            printed,
        )


def test_the_live_api_commands_shown_work_on_the_main_job(tmp_path: Path) -> None:
    """The 'from another terminal' lines, against the main job's world (headless here)."""
    lines = code_blocks(README, "text")[1].splitlines()
    commands = [shlex.split(line.split("#")[0]) for line in lines]
    assert commands and all(command[0] == "armfleet" for command in commands)
    with WorldProcess(tmp_path, "bob", "toby", "--at", "0,0", "1,0", "--no-viewer") as world:
        for command in commands:
            done = cli(tmp_path, *command[1:])
            assert done.returncode == 0, (command, done.stderr)
            assert done.stdout.strip(), command
        with armfleet.connect(world.address) as client:
            (move,) = [command for command in commands if command[1] == "move"]
            target = [float(value) for value in move[move.index("--joints") + 1 : -1]]
            reached = client.arm("bob").positions
        # The position controller holds a target to well under a milliradian at rest.
        assert np.abs(reached - target).max() < HOLD_TOLERANCE_RAD


LINK = re.compile(r"\]\(([^)\s]+)\)")


def heading_anchor(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to dashes."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


@pytest.mark.parametrize(
    "path", markdown_files(), ids=lambda path: path.relative_to(ROOT).as_posix()
)
def test_every_relative_link_reaches_a_file_and_heading(path: Path) -> None:
    links = [link for link in LINK.findall(path.read_text()) if "://" not in link]
    for link in links:
        target, _, anchor = link.partition("#")
        resolved = (path.parent / target).resolve() if target else path
        assert resolved.exists(), f"{path.name}: {link} -> {resolved} does not exist"
        if anchor:
            headings = re.findall(r"^#+ (.+)$", resolved.read_text(), re.MULTILINE)
            anchors = {heading_anchor(heading) for heading in headings}
            assert anchor in anchors, f"{path.name}: {link}: no such heading in {target}"


#: A repository path named in the text, e.g. `benchmarks/fleet.py` or launch_specs/handover.yaml.
REPO_PATH = re.compile(
    r"\b((?:armfleet|benchmarks|examples|controllers|launch_specs|tests|scripts|description)"
    r"/[\w/-]+\.(?:py|yaml|sh|xacro))\b"
)


@pytest.mark.parametrize(
    "path", markdown_files(), ids=lambda path: path.relative_to(ROOT).as_posix()
)
def test_every_repository_file_named_exists(path: Path) -> None:
    named = set(REPO_PATH.findall(path.read_text()))
    missing = sorted(name for name in named if not (ROOT / name).is_file())
    assert not missing, f"{path.name} names files that are not in the repository: {missing}"


def test_the_launch_spec_example_passes_check(tmp_path: Path) -> None:
    (spec,) = code_blocks(DOCS / "descriptions-and-specs.md", "yaml")
    path = tmp_path / "example.yaml"
    path.write_text(spec)
    done = subprocess.run(
        [*ARMFLEET, "launch", str(path), "--check"], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert f"{path}: ok: 31 arm(s) (panda)" in done.stdout  # bob and the 5 x 6 grid


def pages_with_examples() -> list[str]:
    return [
        page
        for page in PAGES
        if (DOCS / page).is_file() and "```python" in (DOCS / page).read_text()
    ]


def test_the_docs_have_examples_and_none_is_left_unrun() -> None:
    assert "manipulation.md" in pages_with_examples()
    for page in pages_with_examples():
        text = (DOCS / page).read_text()
        # Fragments would be fenced some other way and never run: only python blocks exist.
        assert not re.search(r"^```(py|python3)\n", text, re.MULTILINE), page


@pytest.mark.parametrize("page", [p for p in pages_with_examples() if p not in RUN_ELSEWHERE])
def test_docs_python_examples_run_in_order(page: str) -> None:
    blocks = code_blocks(DOCS / page, "python")
    namespace: dict[str, object] = {}
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        for block in blocks:
            exec(compile(block, str(DOCS / page), "exec"), namespace)
    world = namespace["world"]
    assert getattr(world, "closed", False), f"docs/{page}'s examples end with world.close()"
    if page == "manipulation.md":
        check_the_cube_was_lifted(printed.getvalue().splitlines()[-1])


def check_the_cube_was_lifted(last_line: str) -> None:
    """The pick: the last line printed is the cube's position and whether bob holds it."""
    *position, holding = last_line.replace("[", " ").replace("]", " ").replace(",", " ").split()
    x, y, z = (float(value) for value in position)
    assert holding == "True"
    # At rest on the 0.3 m table the 5 cm cube's centre is at 0.325 m; bob lifts it 0.15 m.
    # 5 mm: the most a held box may slip in the tcp (tests/test_gripper.py).
    assert abs(z - (0.325 + 0.15)) < 5e-3, z
    assert abs(x - 0.6) < 5e-3 and abs(y - 0.1) < 5e-3, (x, y)  # where set_pose put it


def test_the_own_robot_commands_shown_work(tmp_path: Path) -> None:
    """The 'Your own robot' lines as typed, the spawn for half a simulated second."""
    lines = code_blocks(README, "text")[3].splitlines()
    commands = [shlex.split(line) for line in lines]
    assert [command[:2] for command in commands] == [
        ["armfleet", "check-model"],
        ["armfleet", "spawn"],
    ]
    env = os.environ | {"XDG_RUNTIME_DIR": str(tmp_path)}
    checked = subprocess.run(
        [*ARMFLEET, *commands[0][1:]], capture_output=True, text=True, env=env, timeout=300
    )
    assert checked.returncode == 0, checked.stderr
    spawned = subprocess.run(
        [*ARMFLEET, *commands[1][1:], "--duration", "0.5", "--no-viewer", "--quiet"],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert spawned.returncode == 0, spawned.stderr
