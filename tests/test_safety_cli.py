"""The protective stop's reset from another terminal: ``armfleet reset NAME``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import armfleet
from tests.remote_world import WorldProcess, cli


def test_cli_reset_lets_touching_arms_move_apart(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    with WorldProcess(tmp_path, "bob", "toby", "--at", "0,0", "0.8,0,0,180", "--no-viewer"):
        home = [0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398]
        lean = list(home)
        lean[1] += 1.0
        lean[3] += 1.2
        with armfleet.connect() as client:
            for name in ("bob", "toby"):
                client.arm(name).move_to(lean)
            for name in ("bob", "toby"):
                with pytest.raises(armfleet.ArmfleetError, match="protective stop"):
                    client.arm(name).wait(timeout=20)
        refused = cli(tmp_path, "move", "bob", "--joints", *map(str, home))
        assert refused.returncode == 2
        assert "reset_stop" in refused.stderr and refused.stderr.count("\n") == 1

        reset = cli(tmp_path, "reset", "bob", "toby")
        assert reset.returncode == 0, reset.stderr
        assert reset.stdout.splitlines() == ["bob: reset", "toby: reset"]
        for name in ("bob", "toby"):
            moved = cli(tmp_path, "move", name, "--joints", *map(str, home), "--wait")
            assert moved.returncode == 0, moved.stderr
        with armfleet.connect() as client:
            for name in ("bob", "toby"):
                position = client.arm(name).joint_state.position[:7]
                assert np.abs(np.asarray(position) - home).max() < 1e-3
