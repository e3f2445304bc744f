"""The README's Python example runs as written, and its two set-up commands are the real ones."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def code_blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README.read_text(), flags=re.DOTALL)


def test_python_example_runs() -> None:
    (example,) = code_blocks("python")
    namespace: dict[str, object] = {}
    exec(compile(example, str(README), "exec"), namespace)
    world = namespace["world"]
    assert getattr(world, "closed", False)


def test_exactly_two_setup_commands_and_ci_runs_the_test_one() -> None:
    commands = [block.strip() for block in code_blocks("bash")]
    assert len(commands) == 2
    assert "armfleet spawn bob toby --at 0,0 1,0" in commands[0]
    ci = (README.parent / ".ci" / "run").read_text()
    assert commands[1] in ci
