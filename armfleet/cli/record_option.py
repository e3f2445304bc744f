"""``--record PATH`` of ``spawn`` and ``launch``: by the file's extension, an MCAP recording
of every topic (``.mcap``) or the viewer's standalone HTML replay (``.html``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from armfleet.cli.parser import UsageError

if TYPE_CHECKING:  # types only; the simulator loads when a world starts
    from armfleet.recording import Recorder
    from armfleet.spec import FleetSpec
    from armfleet.world import World

#: What ``--record`` writes, by extension.
RECORD_KINDS = {
    ".mcap": "an MCAP recording of every topic",
    ".html": "the viewer's standalone HTML replay",
}
METAVAR = "RUN.mcap|RUN.html"
HELP = "record the run: RUN.mcap records every topic (see 'armfleet info/plot/replay'), " + (
    "RUN.html saves the viewer's standalone replay at exit"
)


def check_record_path(path: str | None) -> None:
    """Raise :class:`UsageError` unless ``path`` names a ``.mcap`` or ``.html`` file in an
    existing folder."""
    if path is None:
        return
    target = Path(path)
    if target.suffix.lower() not in RECORD_KINDS:
        kinds = "; ".join(f"{ext} for {what}" for ext, what in RECORD_KINDS.items())
        raise UsageError(f"--record {path}: name a .mcap or .html file ({kinds})")
    folder = target.parent
    if not folder.is_dir():
        raise UsageError(f"--record {path}: the folder {folder} does not exist")


class RunRecording:
    """The recording a command-line run asked for (or none).

    Args:
        path: the ``--record`` value.
        spec: the run's launch spec (stored in an MCAP recording).
        quiet: print nothing (``--quiet``).
    """

    def __init__(self, path: str | None, spec: FleetSpec, *, quiet: bool = False) -> None:
        self._path = None if path is None else Path(path)
        self._spec = spec
        self._quiet = quiet
        self._recorder: Recorder | None = None

    @property
    def needs_viewer(self) -> bool:
        """An HTML replay is the viewer's: it needs one running."""
        return self._path is not None and self._path.suffix.lower() == ".html"

    def start(self, world: World) -> None:
        """Start an MCAP recording of ``world`` (before its first arm comes up)."""
        if self._path is not None and not self.needs_viewer:
            from armfleet.recording.recorder import Recorder

            self._recorder = Recorder(world, self._path, spec=self._spec).start()

    def save(self, world: World) -> None:
        """At the end of the run, with the world still open: write the file."""
        if self.needs_viewer and world.viewer is not None and self._path is not None:
            world.viewer.save(self._path)
            self._say(f"replay saved to {self._path}")
        self.close()

    def close(self) -> None:
        """Complete the MCAP file, whatever happened (idempotent)."""
        recorder = self._recorder
        if recorder is not None and recorder.active:
            recorder.stop()
            size_mb = recorder.path.stat().st_size / 1e6
            self._say(
                f"recording saved to {recorder.path} ({recorder.message_count} messages, "
                f"{size_mb:.1f} MB)"
            )

    def _say(self, line: str) -> None:
        if not self._quiet:
            print(line, flush=True)
