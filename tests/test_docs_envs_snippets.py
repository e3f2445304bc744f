"""Every Python snippet of docs/envs.md runs as a script, as a user pastes it (issue 28,
item 21): each in its own file and interpreter, so that a ``spawn``-ed vector worker
imports it as it would a user's script. Training snippets run with 200 steps instead of
what they show."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parent.parent / "docs" / "envs.md"
SNIPPET = re.compile(r"^```python\n(.*?)^```", re.DOTALL | re.MULTILINE)
#: Training lengths in the docs, shortened here (the test checks they run, not learn).
TRAINING = re.compile(r"total_timesteps=[\d_]+")


def snippets() -> list[str]:
    return SNIPPET.findall(DOC.read_text())


def test_the_vector_and_training_snippets_are_python_blocks() -> None:
    """The snippets users paste are among those run here (a ``text`` block would not be)."""
    found = snippets()
    assert any("AsyncVectorEnv" in code for code in found)
    assert any("stable_baselines3" in code for code in found)
    assert not re.search(r"```text\n[^`]*AsyncVectorEnv", DOC.read_text())


@pytest.mark.parametrize("index", range(len(snippets())))
def test_the_snippet_runs_as_a_script(index: int, tmp_path: Path) -> None:
    code = TRAINING.sub("total_timesteps=200", snippets()[index])
    script = tmp_path / f"snippet_{index}.py"
    script.write_text(code)
    run = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=600, cwd=tmp_path
    )
    assert run.returncode == 0, f"{code}\n--- stderr:\n{run.stderr[-3000:]}"
