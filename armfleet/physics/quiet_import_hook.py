"""PyBullet imported quietly whenever it is first imported, not when armfleet is.

:func:`~armfleet.physics.quiet_pybullet.import_quietly` silences PyBullet's banner by
importing it at once (0.3 s). ``import armfleet`` used to call it, so every command
paid for PyBullet, even one that only asks a running world for its arms. Instead,
:func:`install` puts a finder first on :data:`sys.meta_path` that waits for the first
``import pybullet`` (wherever it happens: a World, a planner, a user's own import after
armfleet's) and loads the module with file descriptor 2 on ``/dev/null``, as
``import_quietly`` does; the finder then removes itself. Import errors still raise.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from types import ModuleType

MODULE = "pybullet"


def install() -> None:
    """Make the first ``import pybullet`` of this process quiet (once; idempotent)."""
    if MODULE in sys.modules or any(isinstance(f, _QuietFinder) for f in sys.meta_path):
        return
    sys.meta_path.insert(0, _QuietFinder())


class _QuietFinder(importlib.abc.MetaPathFinder):
    """Finds :data:`MODULE` as the other finders do, with a loader that keeps it quiet."""

    def find_spec(
        self,
        fullname: str,
        path: Sequence[str] | None,
        target: ModuleType | None = None,
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname != MODULE:
            return None
        sys.meta_path.remove(self)  # once: the other finders find the real module
        spec = importlib.util.find_spec(MODULE)
        if spec is None or spec.loader is None:
            return spec
        spec.loader = _QuietLoader(spec.loader)
        return spec


class _QuietLoader(importlib.abc.Loader):
    """The module's own loader, run with the C-level stderr silenced."""

    def __init__(self, loader: importlib.abc.Loader) -> None:
        self._loader = loader

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        with _silenced_stderr():
            return self._loader.create_module(spec)

    def exec_module(self, module: ModuleType) -> None:
        with _silenced_stderr():
            self._loader.exec_module(module)


@contextmanager
def _silenced_stderr() -> Iterator[None]:
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
