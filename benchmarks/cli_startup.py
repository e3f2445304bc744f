"""How long each ``armfleet`` command takes to show a sign of life, and to finish.

Each command runs in a fresh interpreter (``python -m armfleet.cli.main ...``), its stdout
and stderr read together; the figure is the median over ``--runs`` of the wall time from
the start of the process to its first byte of output, and to its exit. Wall time, so run
it on a quiet machine. The commands: ``--version``, ``models``, ``plot --help``, a real
plot of a short recording, ``sweep`` (2 runs of ``reach`` on 1 worker: the first output is
its progress bar) and a live-API command (``arms``) against a world running in the
background. ``--baseline PATH`` measures another checkout too, the two taking turns run
by run (its package first on the path, the editable install's import hook removed), e.g.
the code before a change (its data folders and compiled kernel linked in):

    mkdir /tmp/before && git archive HEAD armfleet | tar -x -C /tmp/before
    for d in description controllers launch_specs; do ln -s $PWD/$d /tmp/before/$d; done
    cp .venv/lib/python3.11/site-packages/armfleet/controllers/_fleet_kernel*.so \
        /tmp/before/armfleet/controllers/
    python benchmarks/cli_startup.py --baseline /tmp/before

Writes ``benchmarks/results/cli_startup.json`` by default.
"""

from __future__ import annotations

import argparse
import json
import os
import selectors
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
#: An editable install's import hook outranks PYTHONPATH: without it, the tree given is the
#: one imported.
WITHOUT_EDITABLE_HOOK = (
    "import sys; sys.meta_path[:] = [f for f in sys.meta_path "
    "if not type(f).__module__.startswith('_editable_skbc_')]; "
)
#: Longest a measured command may take [s] (a bound against a hang, not a figure).
COMMAND_TIMEOUT_S = 600.0


@dataclass(frozen=True)
class Timing:
    """One command's medians [s] over the runs, and every run's figures."""

    command: str
    first_output_s: float
    exit_s: float
    runs_first_output_s: list[float]
    runs_exit_s: list[float]
    exit_code: int


def _cli(tree: Path | None) -> list[str]:
    """The interpreter and code that run the CLI of ``tree`` (None: this checkout)."""
    code = "import sys; from armfleet.cli.main import main; sys.exit(main(sys.argv[1:]))"
    if tree is not None:
        code = WITHOUT_EDITABLE_HOOK + f"sys.path.insert(0, {str(tree)!r}); " + code
    return [sys.executable, "-c", code]


def time_command(cli: list[str], args: list[str], env: dict[str, str]) -> tuple[float, float, int]:
    """Seconds to the first byte of output, to the exit, and the exit code."""
    began = time.perf_counter()
    process = subprocess.Popen(
        [*cli, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env
    )
    assert process.stdout is not None
    first = None
    with selectors.DefaultSelector() as selector:
        selector.register(process.stdout, selectors.EVENT_READ)
        while True:
            if time.perf_counter() - began > COMMAND_TIMEOUT_S:
                process.kill()
                raise RuntimeError(f"armfleet {' '.join(args)}: no exit in {COMMAND_TIMEOUT_S} s")
            if not selector.select(timeout=0.5):
                continue
            chunk = os.read(process.stdout.fileno(), 65536)
            if not chunk:
                break
            if first is None:
                first = time.perf_counter() - began
    code = process.wait()
    ended = time.perf_counter() - began
    return (first if first is not None else ended), ended, code


@contextmanager
def running_world(cli: list[str], env: dict[str, str]) -> Iterator[None]:
    """A world with one Panda serving the live API until the block ends."""
    process = subprocess.Popen(
        [*cli, "spawn", "bob", "--at", "0,0", "--no-viewer"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        env=env,
        text=True,
    )
    try:
        assert process.stdout is not None
        for line in process.stdout:
            if line.startswith("api: "):
                break
        else:
            raise RuntimeError(f"the world did not start (exit {process.wait()})")
        yield
    finally:
        process.terminate()
        process.wait(timeout=60)


def measure(trees: dict[str, Path | None], runs: int, folder: Path) -> dict[str, list[Timing]]:
    """Each command's timings for each tree, the trees taking turns run by run (so that a
    machine whose load drifts weighs on each alike). The recording and the running world
    are made by the first tree."""
    clis = {label: _cli(tree) for label, tree in trees.items()}
    first = next(iter(clis.values()))
    # Each tree its own runtime folder: its own world for the live-API command (two
    # versions may speak different protocols).
    envs = {label: _env(folder / label) for label in clis}
    env = envs[next(iter(clis))]
    recording = folder / "run.mcap"
    made = subprocess.run(
        [*first, "spawn", "bob", "--at", "0,0", "--no-viewer", "--fast", "--duration", "1",
         "--no-api", "--new-world", "--quiet", "--record", str(recording)],
        env=env, capture_output=True, text=True, check=False,
    )  # fmt: skip
    if made.returncode != 0:
        raise RuntimeError(f"could not record: {made.stderr.strip()[-300:]}")
    commands = {
        "--version": ["--version"],
        "models": ["models"],
        "plot --help": ["plot", "--help"],
        "plot RUN.mcap": ["plot", str(recording), "-o", str(folder)],
        "sweep reach --runs 2": [
            "sweep", "reach", "--runs", "2", "--workers", "1", "--overwrite",
            "-o", str(folder / "sweep.parquet"),
        ],
    }  # fmt: skip
    timings: dict[str, list[Timing]] = {label: [] for label in clis}
    for name, args in commands.items():
        for label, timing in _timed(name, clis, args, envs, runs).items():
            timings[label].append(timing)
    with ExitStack() as worlds:
        for label, cli in clis.items():
            worlds.enter_context(running_world(cli, envs[label]))
        for label, timing in _timed("arms (live API)", clis, ["arms"], envs, runs).items():
            timings[label].append(timing)
    return timings


def _env(runtime_dir: Path) -> dict[str, str]:
    runtime_dir.mkdir(parents=True, exist_ok=True)
    return os.environ | {"XDG_RUNTIME_DIR": str(runtime_dir), "PYTHONUNBUFFERED": "1"}


def _timed(
    name: str,
    clis: dict[str, list[str]],
    args: list[str],
    envs: dict[str, dict[str, str]],
    runs: int,
) -> dict[str, Timing]:
    firsts: dict[str, list[float]] = {label: [] for label in clis}
    exits: dict[str, list[float]] = {label: [] for label in clis}
    codes: dict[str, int] = {}
    for _ in range(runs):
        for label, cli in clis.items():
            first, ended, codes[label] = time_command(cli, args, envs[label])
            firsts[label].append(first)
            exits[label].append(ended)
    timings = {}
    for label in clis:
        timing = Timing(
            name,
            statistics.median(firsts[label]),
            statistics.median(exits[label]),
            firsts[label],
            exits[label],
            codes[label],
        )
        timings[label] = timing
        print(
            f"{label:9s} {name:22s} first output {timing.first_output_s:6.2f} s, "
            f"exit {timing.exit_s:6.2f} s (exit code {timing.exit_code})",
            flush=True,
        )
    return timings


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--baseline", type=Path, help="another armfleet checkout, measured turn by turn"
    )
    parser.add_argument("--runs", type=int, default=3, help="runs per command (median)")
    parser.add_argument(
        "-o", "--output", type=Path, default=HERE / "benchmarks" / "results" / "cli_startup.json"
    )
    args = parser.parse_args()
    trees: dict[str, Path | None] = {"this": None}
    if args.baseline is not None:
        trees["baseline"] = args.baseline.resolve()
    with tempfile.TemporaryDirectory(prefix="armfleet-cli-startup-") as folder:
        timings = measure(trees, args.runs, Path(folder))
    args.output.parent.mkdir(parents=True, exist_ok=True)
    figures = {
        label: {
            "tree": str(trees[label] or HERE),
            "runs": args.runs,
            "commands": [asdict(t) for t in timings[label]],
        }
        for label in trees
    }
    args.output.write_text(json.dumps(figures, indent=2))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
