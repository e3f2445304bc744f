"""What ``import armfleet`` and the CLI's start cost, against another checkout.

Each figure is the median of fresh interpreters (wall time, so run it on a quiet
machine): ``import armfleet``, ``armfleet --version`` (the CLI's whole start) and the
optional packages the import loaded. ``--baseline PATH`` measures another checkout of
armfleet the same way, interleaved run by run, and prints the ratios; the compiled
kernel is not needed for either.

    python benchmarks/import_time.py --baseline /tmp/armfleet-before --runs 15
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

OPTIONAL = ("ray", "pyarrow", "foxglove", "gymnasium", "pettingzoo", "matplotlib", "zmq")
IMPORT = (
    "import sys, json; import armfleet; "
    "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))"
)
CLI = "import sys; from armfleet.cli.main import main; sys.argv=['armfleet', '--version']; main()"


#: An editable install's import hook outranks PYTHONPATH: without it, the tree given is the
#: one imported.
WITHOUT_EDITABLE_HOOK = (
    "import sys; sys.meta_path[:] = [f for f in sys.meta_path "
    "if not type(f).__module__.startswith('_editable_skbc_')]; "
)


def _run(code: str, tree: Path | None) -> tuple[float, str]:
    env = dict(os.environ)
    if tree is not None:  # that checkout's package first on the path, and the one imported
        env["PYTHONPATH"] = str(tree)
        code = WITHOUT_EDITABLE_HOOK + code
    started = time.perf_counter()
    result = subprocess.run(  # run in the tree: -c puts the working folder first on the path
        [sys.executable, "-c", code],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
        check=False,
    )
    elapsed = time.perf_counter() - started
    if result.returncode not in (0,) and "armfleet" not in result.stdout:
        raise RuntimeError(result.stderr.strip().splitlines()[-1])
    return elapsed, result.stdout


@dataclass(frozen=True)
class Figures:
    """Medians over fresh interpreters [s], and what the import loaded."""

    interpreter_s: float
    import_s: float
    cli_version_s: float
    optional_loaded: list[str]
    modules_loaded: int


def measure(tree: Path | None, runs: int) -> Figures:
    imports = [_run(IMPORT, tree)[0] for _ in range(runs)]
    clis = [_run(CLI, tree)[0] for _ in range(runs)]
    loaded = set(json.loads(_run(IMPORT, tree)[1]))
    return Figures(
        interpreter_s=statistics.median(_run("pass", tree)[0] for _ in range(runs)),
        import_s=statistics.median(imports),
        cli_version_s=statistics.median(clis),
        optional_loaded=sorted(loaded & set(OPTIONAL)),
        modules_loaded=len(loaded),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path, help="another armfleet checkout to compare")
    parser.add_argument("--runs", type=int, default=11, help="fresh interpreters per figure")
    parser.add_argument("-o", "--output", type=Path, default=Path("import_time.json"))
    args = parser.parse_args()
    here = Path(__file__).resolve().parents[1]
    figures = {"this": measure(here, args.runs)}
    if args.baseline is not None:
        figures["baseline"] = measure(args.baseline.resolve(), args.runs)
    for name, f in figures.items():
        print(
            f"{name:8s} import armfleet {f.import_s * 1e3:6.0f} ms, armfleet --version "
            f"{f.cli_version_s * 1e3:6.0f} ms (bare interpreter {f.interpreter_s * 1e3:.0f} ms, "
            f"{f.modules_loaded} modules); optional packages loaded: "
            f"{', '.join(f.optional_loaded) or 'none'}"
        )
    if "baseline" in figures:
        this, base = figures["this"], figures["baseline"]
        print(f"import: baseline / this = {base.import_s / this.import_s:.2f}x")
        print(f"CLI start: baseline / this = {base.cli_version_s / this.cli_version_s:.2f}x")
    args.output.write_text(json.dumps({k: asdict(f) for k, f in figures.items()}, indent=2))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
